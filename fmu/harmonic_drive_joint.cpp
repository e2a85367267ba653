// HarmonicDriveJoint.fmu: the joint itself (motor, harmonic drive, link with
// gravity) for reference trajectories and system simulation.
#include <optional>

#include "hdjoint/joint_plant.h"
#include "model.h"
#include "parameter_access.h"

namespace hdjoint::fmu {

namespace {

enum : unsigned {
    kIm = 100, kTauExt,
    kThetaM = 200, kThetaL, kTauJoint, kOmegaM, kOmegaL,
};

class JointModel final : public Model {
public:
    double get(unsigned vr) const override {
        if (is_parameter(vr)) return parameter_value(p_, vr);
        switch (vr) {
            case kIm: return in_.i_m;
            case kTauExt: return in_.tau_ext;
            case kThetaM: return out_.theta_m;
            case kThetaL: return out_.theta_l;
            case kTauJoint: return out_.tau_joint;
            case kOmegaM: return out_.omega_m;
            case kOmegaL: return out_.omega_l;
        }
        return 0.0;
    }

    Result set(unsigned vr, double value) override {
        if (is_parameter(vr)) parameter_ref(p_, vr) = value;
        else if (vr == kIm) in_.i_m = value;
        else if (vr == kTauExt) in_.tau_ext = value;
        return Result::ok();
    }

    Result initialize(double /*start_time*/) override {
        if (auto problem = validate(p_, false, true)) return Result::error(*problem);
        plant_.emplace(p_);
        std::string message;
        if (!plant_->initialize(in_.tau_ext, &message)) return Result::error(message);
        out_ = plant_->outputs();
        return Result::ok();
    }

    Result do_step(double /*t*/, double h) override {
        std::string message;
        if (!plant_->advance(h, in_, &message)) return Result::error(message);
        out_ = plant_->outputs();
        return Result::ok();
    }

    void reset() override { *this = JointModel(); }

    std::vector<double> save() const override {
        std::vector<double> d;
        append_parameters(p_, &d);
        d.insert(d.end(), {in_.i_m, in_.tau_ext, out_.theta_m, out_.theta_l, out_.tau_joint, out_.omega_m,
                           out_.omega_l, plant_ ? 1.0 : 0.0});
        if (plant_) {
            const std::vector<double> s = plant_->save_state();
            d.insert(d.end(), s.begin(), s.end());
        }
        return d;
    }

    bool load(const std::vector<double>& d) override {
        std::size_t k = 0;
        JointModel m;
        if (!read_parameters(d, &k, &m.p_) || d.size() < k + 8) return false;
        m.in_ = {d[k], d[k + 1]};
        m.out_ = {d[k + 2], d[k + 3], d[k + 4], d[k + 5], d[k + 6]};
        const bool has_plant = d[k + 7] != 0.0;
        k += 8;
        if (has_plant) {
            m.plant_.emplace(m.p_);
            if (!m.plant_->load_state(std::vector<double>(d.begin() + static_cast<long>(k), d.end()))) return false;
        } else if (k != d.size()) {
            return false;
        }
        *this = std::move(m);
        return true;
    }

private:
    Parameters p_;
    PlantInputs in_;
    PlantOutputs out_;
    std::optional<JointPlant> plant_;
};

ModelInfo make_info() {
    ModelInfo info;
    info.model_name = "HarmonicDriveJoint";
    info.model_identifier = "HarmonicDriveJoint";
    info.description =
        "A robot joint with a harmonic drive: DC motor (Yu et al. 2018, eq. 2), wave generator and flexspline "
        "compliance with kinematic error (eq. 3-8), link inertia, damping and gravity, quantised encoders.";
    info.variables = parameter_variables(false, true);
    const double inf = 1e300;
    info.variables.push_back({"i_m", kIm, Causality::Input, "A", "motor current", 0.0, -inf, inf});
    info.variables.push_back({"tau_ext", kTauExt, Causality::Input, "N.m",
                              "external load torque on the link, in the sense of gravity's mgl*sin(theta_l)", 0.0, -inf, inf});
    info.variables.push_back({"theta_m", kThetaM, Causality::Output, "rad", "motor encoder reading (quantised by motor_counts)", 0.0});
    info.variables.push_back({"theta_l", kThetaL, Causality::Output, "rad", "link encoder reading (quantised by link_counts)", 0.0});
    info.variables.push_back({"tau_joint", kTauJoint, Causality::Output, "N.m", "torque transmitted by the flexspline (what a torque sensor reads)", 0.0});
    info.variables.push_back({"omega_m", kOmegaM, Causality::Output, "rad/s", "true motor speed", 0.0});
    // CONTRACT.md names this output omega_l, which collides with the eq. (7)
    // parameter omega_l that every parameter set uses; FMI names must be unique.
    info.variables.push_back({"omega_link", kOmegaL, Causality::Output, "rad/s",
                              "true link speed (CONTRACT.md's omega_l output; renamed: omega_l is the eq. (7) parameter)", 0.0});
    info.create = [] { return std::unique_ptr<Model>(new JointModel()); };
    return info;
}

}  // namespace

const ModelInfo& this_model() {
    static const ModelInfo info = make_info();
    return info;
}

}  // namespace hdjoint::fmu
