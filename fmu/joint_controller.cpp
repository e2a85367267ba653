// JointController.fmu: link position PD with optional joint torque feedback,
// plus the reference and the external load, for system simulation with
// HarmonicDriveJoint.fmu and JointTorqueEstimator.fmu.
#include <optional>

#include "hdjoint/joint_controller.h"
#include "model.h"

namespace hdjoint::fmu {

namespace {

enum : unsigned {
    kThetaM = 100, kThetaL, kTauFb,
    kIm = 200, kTauExt, kThetaRef, kTauD, kELink,
};

bool is_parameter(unsigned vr) { return vr < controller_parameter_count(); }
double& parameter_ref(ControllerParameters& p, unsigned vr) { return p.*(controller_parameter_table()[vr].member); }
double parameter_value(const ControllerParameters& p, unsigned vr) {
    return p.*(controller_parameter_table()[vr].member);
}

class ControllerModel final : public Model {
public:
    double get(unsigned vr) const override {
        if (is_parameter(vr)) return parameter_value(p_, vr);
        switch (vr) {
            case kThetaM: return in_.theta_m;
            case kThetaL: return in_.theta_l;
            case kTauFb: return in_.tau_fb;
            case kIm: return out_.i_m;
            case kTauExt: return out_.tau_ext;
            case kThetaRef: return out_.theta_ref;
            case kTauD: return out_.tau_d;
            case kELink: return out_.e_link;
        }
        return 0.0;
    }

    Result set(unsigned vr, double value) override {
        if (is_parameter(vr)) parameter_ref(p_, vr) = value;
        else if (vr == kThetaM) in_.theta_m = value;
        else if (vr == kThetaL) in_.theta_l = value;
        else if (vr == kTauFb) in_.tau_fb = value;
        return Result::ok();
    }

    Result initialize(double start_time) override {
        if (auto problem = validate(p_)) return Result::error(*problem);
        controller_.emplace(p_, start_time);
        out_ = controller_->outputs();
        return Result::ok();
    }

    Result do_step(double t, double h) override {
        controller_->advance(t, h, in_);
        out_ = controller_->outputs();
        return Result::ok();
    }

    void reset() override { *this = ControllerModel(); }

    std::vector<double> save() const override {
        std::vector<double> d;
        for (unsigned i = 0; i < controller_parameter_count(); ++i) d.push_back(parameter_value(p_, i));
        d.insert(d.end(), {in_.theta_m, in_.theta_l, in_.tau_fb, out_.i_m, out_.tau_ext, out_.theta_ref, out_.tau_d,
                           out_.e_link, controller_ ? 1.0 : 0.0});
        if (controller_) {
            const std::vector<double> s = controller_->save_state();
            d.insert(d.end(), s.begin(), s.end());
        }
        return d;
    }

    bool load(const std::vector<double>& d) override {
        const std::size_t n = controller_parameter_count();
        if (d.size() < n + 9) return false;
        ControllerModel m;
        for (unsigned i = 0; i < n; ++i) parameter_ref(m.p_, i) = d[i];
        std::size_t k = n;
        m.in_ = {d[k], d[k + 1], d[k + 2]};
        m.out_ = {d[k + 3], d[k + 4], d[k + 5], d[k + 6], d[k + 7]};
        const bool has_controller = d[k + 8] != 0.0;
        k += 9;
        if (has_controller) {
            m.controller_.emplace(m.p_);
            if (!m.controller_->load_state(std::vector<double>(d.begin() + static_cast<long>(k), d.end())))
                return false;
        } else if (k != d.size()) {
            return false;
        }
        *this = std::move(m);
        return true;
    }

private:
    ControllerParameters p_;
    ControllerInputs in_;
    ControllerOutputs out_;
    std::optional<JointController> controller_;
};

ModelInfo make_info() {
    ModelInfo info;
    info.model_name = "JointController";
    info.model_identifier = "JointController";
    info.description =
        "Controller of a harmonic-drive joint: link position PD on the motor encoder with gravity feed-forward and "
        "an optional inner joint-torque loop (joint torque feedback) on tau_fb, the UKF estimate or a torque sensor; "
        "generates the link reference (a sinusoid) and the external load disturbance tau_ext. Sampled at Ts.";
    const ControllerParameterInfo* table = controller_parameter_table();
    for (unsigned i = 0; i < controller_parameter_count(); ++i)
        info.variables.push_back({table[i].name, i, Causality::Parameter, table[i].unit, table[i].description,
                                  table[i].default_value, table[i].min, table[i].max});
    const double inf = 1e300;
    info.variables.push_back({"theta_m", kThetaM, Causality::Input, "rad", "motor encoder angle (multi-turn)", 0.0, -inf, inf});
    info.variables.push_back({"theta_l", kThetaL, Causality::Input, "rad", "link encoder angle (for e_link; the law does not use it)", 0.0, -inf, inf});
    info.variables.push_back({"tau_fb", kTauFb, Causality::Input, "N.m",
                              "joint torque fed back when jtf = 1: the estimator's tau_ukf, or a torque sensor (the joint's tau_joint)", 0.0, -inf, inf});
    info.variables.push_back({"i_m", kIm, Causality::Output, "A", "motor current command (saturated to +-i_max)", 0.0});
    info.variables.push_back({"tau_ext", kTauExt, Causality::Output, "N.m", "external load disturbance for the joint's tau_ext input", 0.0});
    info.variables.push_back({"theta_ref", kThetaRef, Causality::Output, "rad", "link position reference", 0.0});
    info.variables.push_back({"tau_d", kTauD, Causality::Output, "N.m", "joint torque the position loop asks for (the torque loop's set point)", 0.0});
    info.variables.push_back({"e_link", kELink, Causality::Output, "rad", "link position error theta_ref - theta_l at the last sample", 0.0});
    info.create = [] { return std::unique_ptr<Model>(new ControllerModel()); };
    return info;
}

}  // namespace

const ModelInfo& this_model() {
    static const ModelInfo info = make_info();
    return info;
}

}  // namespace hdjoint::fmu
