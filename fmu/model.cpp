#include "model.h"

namespace hdjoint::fmu {

const Variable* find_variable(const ModelInfo& info, unsigned vr) {
    for (const Variable& v : info.variables)
        if (v.value_reference == vr) return &v;
    return nullptr;
}

}  // namespace hdjoint::fmu
