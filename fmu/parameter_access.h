#pragma once
// Parameters by FMI value reference (the index in parameter_table.def), and
// their flat copy for FMU state; shared by every hdjoint FMU.
#include <vector>

#include "hdjoint/parameters.h"

namespace hdjoint::fmu {

inline bool is_parameter(unsigned vr) { return vr < parameter_count(); }
inline double& parameter_ref(Parameters& p, unsigned vr) { return p.*(parameter_table()[vr].member); }
inline double parameter_value(const Parameters& p, unsigned vr) { return p.*(parameter_table()[vr].member); }

inline void append_parameters(const Parameters& p, std::vector<double>* out) {
    for (unsigned i = 0; i < parameter_count(); ++i) out->push_back(parameter_value(p, i));
}
// Reads parameter_count() values from `*cursor` on; false when too few remain.
inline bool read_parameters(const std::vector<double>& in, std::size_t* cursor, Parameters* p) {
    if (in.size() < *cursor + parameter_count()) return false;
    for (unsigned i = 0; i < parameter_count(); ++i) parameter_ref(*p, i) = in[(*cursor)++];
    return true;
}

}  // namespace hdjoint::fmu
