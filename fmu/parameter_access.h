#pragma once
// Parameters by FMI value reference (the index in their table), for both
// parameter tables: the joint's Parameters (parameter_table.def) and the
// controller's ControllerParameters (controller_table.def).
#include <cstddef>

#include "hdjoint/joint_controller.h"
#include "hdjoint/parameters.h"

namespace hdjoint::fmu {

template <class Params>
struct ParameterRows;
template <>
struct ParameterRows<Parameters> {
    static const ParameterInfo* table() { return parameter_table(); }
    static std::size_t count() { return parameter_count(); }
};
template <>
struct ParameterRows<ControllerParameters> {
    static const ControllerParameterInfo* table() { return controller_parameter_table(); }
    static std::size_t count() { return controller_parameter_count(); }
};

template <class Params>
bool is_parameter(unsigned vr) {
    return vr < ParameterRows<Params>::count();
}
template <class Params>
double& parameter_ref(Params& p, unsigned vr) {
    return p.*(ParameterRows<Params>::table()[vr].member);
}
template <class Params>
double parameter_value(const Params& p, unsigned vr) {
    return p.*(ParameterRows<Params>::table()[vr].member);
}

// Every parameter as a named state field, read back within its valid range.
template <class Archive, class Params>
bool parameter_fields(Archive& a, Params& p) {
    for (std::size_t i = 0; i < ParameterRows<Params>::count(); ++i) {
        const auto& row = ParameterRows<Params>::table()[i];
        if (!a(row.name, p.*(row.member), row.min, row.max)) return false;
    }
    return true;
}

}  // namespace hdjoint::fmu
