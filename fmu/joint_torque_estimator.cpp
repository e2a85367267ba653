// JointTorqueEstimator.fmu: the paper's compliance model and UKF on encoder
// angles and motor current, sampled at the fixed period Ts. Its variables are
// declared in src/hdjoint/estimator_signals.def and parameter_table.def.
#include "hdjoint/torque_estimator.h"
#include "table_model.h"

namespace hdjoint::fmu {

namespace {

class EstimatorModel final : public TableModel<Parameters, EstimatorInputs, EstimatorOutputs, TorqueEstimator> {
public:
    EstimatorModel()
        : TableModel(estimator_signals(), [](const Parameters& p) { return validate(p, true, false); }) {}

private:
    Result start() override {
        core_->show_start(in_);
        return Result::ok();
    }
    // A step [t, t+h) runs the samples inside it with the inputs set at t.
    Result step(double t, double h) override {
        std::string message;
        const EstimatorStatus s = core_->advance_to(t + h, t, in_, &message);
        // A run of gated readings is said once, at its first (the others are counted by the core).
        if (s == EstimatorStatus::Ok || (s == EstimatorStatus::ReadingGated && message.empty())) return Result::ok();
        return recoverable(s) ? Result::warning(message) : Result::error(message);
    }
};

}  // namespace

const ModelInfo& this_model() {
    return describe_model<EstimatorModel>(HDJ_ESTIMATOR_FMU,
        [](const ParameterInfo& row) { return in_estimator(row.scope); });
}

}  // namespace hdjoint::fmu
