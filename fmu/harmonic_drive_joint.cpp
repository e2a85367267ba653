// HarmonicDriveJoint.fmu: the joint itself (motor, harmonic drive, link with
// gravity) for reference trajectories and system simulation. Its variables
// are declared in src/hdjoint/plant_signals.def and parameter_table.def.
#include "hdjoint/joint_plant.h"
#include "table_model.h"

namespace hdjoint::fmu {

namespace {

class JointModel final : public TableModel<Parameters, PlantInputs, PlantOutputs, JointPlant> {
public:
    JointModel()
        : TableModel(plant_signals(), [](const Parameters& p) { return validate(p, false, true); }) {}

private:
    Result start() override {
        std::string message;
        return core_->initialize(in_.tau_ext, &message) ? Result::ok() : Result::error(message);
    }
    Result step(double, double h) override {
        std::string message;
        return core_->advance(h, in_, &message) ? Result::ok() : Result::error(message);
    }
};

}  // namespace

const ModelInfo& this_model() {
    return describe_model<JointModel>(HDJ_PLANT_FMU,
        [](const ParameterInfo& row) { return in_plant(row.scope); });
}

}  // namespace hdjoint::fmu
