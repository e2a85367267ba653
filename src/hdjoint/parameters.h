#pragma once
// Model parameters, generated from parameter_table.def (the one source of truth).
#include <cstddef>
#include <optional>
#include <string>

namespace hdjoint {

enum class Scope { Shared, Plant, Estimator };

// All parameters as plain data, so instance state can be copied byte-wise.
struct Parameters {
#define HDJ_PARAMETER(name, unit, def, lo, hi, scope, description) double name = def;
#include "parameter_table.def"
#undef HDJ_PARAMETER
};

struct ParameterInfo {
    const char* name;
    const char* unit;
    double default_value;
    double min;
    double max;
    Scope scope;
    const char* description;
    double Parameters::*member;
};

// The table, in declaration order; the index is stable and is used as the
// FMI value reference of each parameter in both FMUs.
const ParameterInfo* parameter_table();
std::size_t parameter_count();

// The calibration prior of a parameter (parameter_tolerance.def): one
// standard deviation max(relative*|nominal|, absolute); `source` cites it.
struct ToleranceInfo {
    const char* name;
    double relative;
    double absolute;
    const char* source;
};
const ToleranceInfo* tolerance_table();
std::size_t tolerance_count();
// The tolerance row of a parameter, or nothing when it is never calibrated.
const ToleranceInfo* find_tolerance(const std::string& name);

// Index of a parameter by name, or nothing.
std::optional<std::size_t> find_parameter(const std::string& name);

// Whether the parameter belongs to the estimator FMU / the joint FMU.
bool in_estimator(Scope s);
bool in_plant(Scope s);

// The estimator's current-to-encoder delay in whole samples, round(i_delay/Ts);
// at most kMaxDelaySamples (validate() says so).
constexpr long kMaxDelaySamples = 128;
long delay_samples(const Parameters& p);

// The fewest encoder counts per revolution that quantise (0 switches quantisation off).
constexpr double kMinEncoderCounts = 1.0;

// First problem with a parameter set (name and value), or nothing when the
// whole set is valid. `estimator` and `plant` check only the parameters those carry.
std::optional<std::string> validate(const Parameters& p, bool estimator, bool plant);

}  // namespace hdjoint
