// JointController.fmu: link position PD with optional joint torque feedback,
// plus the reference and the external load, for system simulation with
// HarmonicDriveJoint.fmu and JointTorqueEstimator.fmu. Its variables are
// declared in src/hdjoint/controller_signals.def and controller_table.def.
#include "hdjoint/joint_controller.h"
#include "table_model.h"

namespace hdjoint::fmu {

namespace {

class ControllerModel final
    : public TableModel<ControllerParameters, ControllerInputs, ControllerOutputs, JointController> {
public:
    ControllerModel()
        : TableModel(controller_signals(), [](const ControllerParameters& p) { return validate(p); }) {}

private:
    Result start() override { return Result::ok(); }
    Result step(double t, double h) override {
        std::string message;
        return core_->advance(t, h, in_, &message) ? Result::ok() : Result::error(message);
    }
};

}  // namespace

const ModelInfo& this_model() {
    return describe_model<ControllerModel>(HDJ_CONTROLLER_FMU,
        [](const ControllerParameterInfo&) { return true; });
}

}  // namespace hdjoint::fmu
