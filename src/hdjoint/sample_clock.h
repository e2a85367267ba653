#pragma once
// The fixed-rate sample grid of a sampled model (the estimator, the
// controller): sample k falls at start + k*Ts, computed from k so no
// round-off builds up. A communication step [t, t+h) runs the samples
// before t + h (within a millionth of Ts), whatever h is.
//
// A step is bounded: one that would run more than kMaxSamplesPerStep samples
// is refused whole (nothing runs), never looped through for hours.
#include <cmath>
#include <cstdio>
#include <string>

#include "state_fields.h"

namespace hdjoint {

class SampleClock {
public:
    // 2*10^5 samples: 200 s at 1 kHz, well under a second of computing.
    static constexpr long kMaxSamplesPerStep = 200000;

    SampleClock(double start_time, double Ts) : start_(start_time), Ts_(Ts) {}

    // Runs `sample(t_k)` for each sample due before `end` (stopping early
    // when it returns false, which it returns as well). False with a message,
    // and no sample run, when more than kMaxSamplesPerStep are due.
    template <class Sample>
    bool run_until(double end, Sample sample, std::string* message = nullptr) {
        const double tolerance = 1e-6 * Ts_;
        const double due = (end - tolerance - start_) / Ts_ - static_cast<double>(next_);
        if (!(due <= static_cast<double>(kMaxSamplesPerStep))) {
            if (message) {
                *message = "a step to t = " + format_count(end) + " s would run " + format_count(std::ceil(due)) +
                           " samples of Ts = " + format_count(Ts_) + " s; at most " +
                           std::to_string(kMaxSamplesPerStep) + " are allowed per step: split the step";
            }
            return false;
        }
        while (start_ + static_cast<double>(next_) * Ts_ < end - tolerance) {
            const double t = start_ + static_cast<double>(next_) * Ts_;
            ++next_;
            if (!sample(t)) return false;
        }
        return true;
    }

    // A count or time as a person reads it: "3e+305", "1000", "unbounded"
    // (never through an integer type a huge count would overflow).
    static std::string format_count(double v) {
        if (!std::isfinite(v)) return "unbounded";
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.6g", v);
        return buf;
    }

    double start_time() const { return start_; }
    long next_sample() const { return next_; }

    template <class Archive>
    bool fields(Archive& a) {
        return a("clock_start_time", start_, -kUnbounded, kUnbounded) && a("clock_next_sample", next_);
    }

private:
    double start_;
    double Ts_;
    long next_ = 0;
};

}  // namespace hdjoint
