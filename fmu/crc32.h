#pragma once
// CRC-32 (IEEE 802.3, the polynomial of zlib, PNG and gzip: zlib.crc32 gives
// the same value), which seals a serialised FMU state so any edit of it is
// found. Bitwise, without a table: states are a few kB, serialised rarely.
#include <cstddef>
#include <cstdint>

namespace hdjoint::fmu {

inline std::uint32_t crc32(const unsigned char* data, std::size_t size) {
    std::uint32_t crc = 0xFFFFFFFFu;
    for (std::size_t i = 0; i < size; ++i) {
        crc ^= data[i];
        for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

}  // namespace hdjoint::fmu
