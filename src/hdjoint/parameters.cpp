#include "parameters.h"

#include <cmath>
#include <cstring>
#include <sstream>
#include <utility>

namespace hdjoint {

namespace {
const ParameterInfo kTable[] = {
#define HDJ_PARAMETER(name, unit, def, lo, hi, scope, description) \
    {#name, unit, def, lo, hi, Scope::scope, description, &Parameters::name},
#include "parameter_table.def"
#undef HDJ_PARAMETER
};
constexpr std::size_t kCount = sizeof(kTable) / sizeof(kTable[0]);
const ToleranceInfo kTolerances[] = {
#define HDJ_TOLERANCE(name, relative, absolute, source) {#name, relative, absolute, source},
#include "parameter_tolerance.def"
#undef HDJ_TOLERANCE
};
constexpr std::size_t kToleranceCount = sizeof(kTolerances) / sizeof(kTolerances[0]);
// A parameter's value reference is its index; the FMUs number inputs from 100.
static_assert(kCount < 100, "parameter value references would collide with the FMUs' inputs (100+)");
}  // namespace

const ParameterInfo* parameter_table() { return kTable; }
std::size_t parameter_count() { return kCount; }

const ToleranceInfo* tolerance_table() { return kTolerances; }
std::size_t tolerance_count() { return kToleranceCount; }

const ToleranceInfo* find_tolerance(const std::string& name) {
    for (std::size_t i = 0; i < kToleranceCount; ++i)
        if (name == kTolerances[i].name) return &kTolerances[i];
    return nullptr;
}

std::optional<std::size_t> find_parameter(const std::string& name) {
    for (std::size_t i = 0; i < kCount; ++i)
        if (name == kTable[i].name) return i;
    return std::nullopt;
}

long delay_samples(const Parameters& p) { return std::lround(p.i_delay / p.Ts); }

bool in_estimator(Scope s) { return s == Scope::Shared || s == Scope::Estimator; }
bool in_plant(Scope s) { return s == Scope::Shared || s == Scope::Plant; }

std::optional<std::string> validate(const Parameters& p, bool estimator, bool plant) {
    for (std::size_t i = 0; i < kCount; ++i) {
        const ParameterInfo& info = kTable[i];
        if (!((estimator && in_estimator(info.scope)) || (plant && in_plant(info.scope)))) continue;
        const double v = p.*(info.member);
        if (!std::isfinite(v) || v < info.min || v > info.max) {
            std::ostringstream msg;
            msg.precision(17);
            msg << "parameter " << info.name << " = " << v << " is outside its valid range ["
                << info.min << ", " << info.max << "] " << info.unit;
            return msg.str();
        }
    }
    // An encoder with less than one count per revolution cannot quantise
    // (2*pi/counts overflows for counts near 5e-324): 0 (off) or >= 1.
    for (const auto& [name, counts] : {std::pair{"motor_counts", p.motor_counts}, std::pair{"link_counts", p.link_counts}}) {
        if (counts != 0.0 && counts < kMinEncoderCounts) {
            std::ostringstream msg;
            msg.precision(17);
            msg << "parameter " << name << " = " << counts << " is below " << kMinEncoderCounts
                << " count per revolution; use 0 to disable quantisation";
            return msg.str();
        }
    }
    if (estimator && delay_samples(p) > kMaxDelaySamples) {
        std::ostringstream msg;
        msg.precision(17);
        msg << "parameter i_delay = " << p.i_delay << " s is " << delay_samples(p) << " samples of Ts = " << p.Ts
            << " s; the estimator delays the encoders by at most " << kMaxDelaySamples << " samples";
        return msg.str();
    }
    return std::nullopt;
}

}  // namespace hdjoint
