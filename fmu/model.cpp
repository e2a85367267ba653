#include "model.h"

#include "hdjoint/parameters.h"

namespace hdjoint::fmu {

std::vector<Variable> parameter_variables(bool estimator, bool plant) {
    std::vector<Variable> vars;
    const ParameterInfo* table = parameter_table();
    for (std::size_t i = 0; i < parameter_count(); ++i) {
        const ParameterInfo& p = table[i];
        if ((estimator && in_estimator(p.scope)) || (plant && in_plant(p.scope)))
            vars.push_back({p.name, static_cast<unsigned>(i), Causality::Parameter, p.unit, p.description,
                            p.default_value, p.min, p.max});
    }
    return vars;
}

const Variable* find_variable(const ModelInfo& info, unsigned vr) {
    for (const Variable& v : info.variables)
        if (v.value_reference == vr) return &v;
    return nullptr;
}

}  // namespace hdjoint::fmu
