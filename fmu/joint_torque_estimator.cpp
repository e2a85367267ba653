// JointTorqueEstimator.fmu: the paper's compliance model and UKF on encoder
// angles and motor current, sampled at the fixed period Ts.
#include <cmath>
#include <optional>

#include "hdjoint/torque_estimator.h"
#include "hdjoint/transmission.h"
#include "model.h"
#include "parameter_access.h"

namespace hdjoint::fmu {

namespace {

enum : unsigned {
    kIm = 100, kThetaM, kThetaL,
    kTauUkf = 200, kTauCompliance, kOmegaM, kDthetaF, kTauUkfStd,
    kTauHat = 205, kTauHatStd,
};

class EstimatorModel final : public Model {
public:
    double get(unsigned vr) const override {
        if (is_parameter(vr)) return parameter_value(p_, vr);
        switch (vr) {
            case kIm: return in_.i_m;
            case kThetaM: return in_.theta_m;
            case kThetaL: return in_.theta_l;
            case kTauUkf: return out_.tau_ukf;
            case kTauCompliance: return out_.tau_compliance;
            case kOmegaM: return out_.omega_m;
            case kDthetaF: return out_.dtheta_f;
            case kTauUkfStd: return out_.tau_ukf_std;
            case kTauHat: return out_.tau_hat;
            case kTauHatStd: return out_.tau_hat_std;
        }
        return 0.0;
    }

    Result set(unsigned vr, double value) override {
        if (is_parameter(vr)) parameter_ref(p_, vr) = value;
        else if (vr == kIm) in_.i_m = value;
        else if (vr == kThetaM) in_.theta_m = value;
        else if (vr == kThetaL) in_.theta_l = value;
        return Result::ok();
    }

    Result initialize(double start_time) override {
        if (auto problem = validate(p_, true, false)) return Result::error(*problem);
        estimator_.emplace(p_);
        start_time_ = start_time;
        next_sample_ = 0;
        // Until the first sample, outputs show the compliance model on the start inputs.
        const ComplianceEstimate c = compliance_estimate(in_.i_m, in_.theta_m, in_.theta_l, p_);
        out_ = {};
        if (c.valid) out_ = {c.tau, c.tau, 0.0, c.dtheta_f, p_.ukf_p0_tau, 0.0, 0.0, c.tau, p_.jsf_p0_load, 0.0};
        return Result::ok();
    }

    // Samples fall at start + k*Ts; a step [t, t+h) processes those inside it
    // with the inputs set at t, whatever h is (multiple of Ts or not).
    Result do_step(double t, double h) override {
        const double tolerance = 1e-6 * p_.Ts;
        Result worst;
        while (start_time_ + static_cast<double>(next_sample_) * p_.Ts < t + h - tolerance) {
            std::string message;
            const EstimatorStatus s = estimator_->step(in_, &message);
            if (!recoverable(s)) return Result::error(message);
            ++next_sample_;
            if (s != EstimatorStatus::Ok && worst.status == Status::Ok) worst = Result::warning(message);
        }
        out_ = estimator_->outputs();
        return worst;
    }

    void reset() override { *this = EstimatorModel(); }

    std::vector<double> save() const override {
        std::vector<double> d;
        append_parameters(p_, &d);
        d.insert(d.end(), {in_.i_m, in_.theta_m, in_.theta_l, start_time_, static_cast<double>(next_sample_),
                           out_.tau_ukf, out_.tau_compliance, out_.omega_m, out_.dtheta_f, out_.tau_ukf_std,
                           out_.nis, out_.tau_hat, out_.tau_hat_std, estimator_ ? 1.0 : 0.0});
        if (estimator_) {
            const std::vector<double> e = estimator_->save_state();
            d.insert(d.end(), e.begin(), e.end());
        }
        return d;
    }

    bool load(const std::vector<double>& d) override {
        std::size_t k = 0;
        EstimatorModel m;
        if (!read_parameters(d, &k, &m.p_) || d.size() < k + 14) return false;
        m.in_ = {d[k], d[k + 1], d[k + 2]};
        m.start_time_ = d[k + 3];
        m.next_sample_ = static_cast<long>(d[k + 4]);
        m.out_ = {d[k + 5], d[k + 6], d[k + 7], d[k + 8], d[k + 9], d[k + 10], 0.0, d[k + 11], d[k + 12], 0.0};
        const bool has_estimator = d[k + 13] != 0.0;
        k += 14;
        if (has_estimator) {
            m.estimator_.emplace(m.p_);
            if (!m.estimator_->load_state(std::vector<double>(d.begin() + static_cast<long>(k), d.end()))) return false;
        } else if (k != d.size()) {
            return false;
        }
        *this = std::move(m);
        return true;
    }

private:
    Parameters p_;
    EstimatorInputs in_;
    EstimatorOutputs out_;
    std::optional<TorqueEstimator> estimator_;
    double start_time_ = 0.0;
    long next_sample_ = 0;
};

ModelInfo make_info() {
    ModelInfo info;
    info.model_name = "JointTorqueEstimator";
    info.model_identifier = "JointTorqueEstimator";
    info.description =
        "Joint torque of a harmonic-drive joint from motor current and motor/link encoder angles: the compliance "
        "model (Yu et al. 2018, eq. 3-8) and the paper's Unscented Kalman Filter (eq. 9-31), at a fixed sample "
        "period Ts; and beyond the paper, the joint-state filter's estimate tau_hat.";
    info.variables = parameter_variables(true, false);
    const double inf = 1e300;
    info.variables.push_back({"i_m", kIm, Causality::Input, "A", "motor current", 0.0, -inf, inf});
    info.variables.push_back({"theta_m", kThetaM, Causality::Input, "rad", "motor-side encoder angle (multi-turn)", 0.0, -inf, inf});
    info.variables.push_back({"theta_l", kThetaL, Causality::Input, "rad", "link-side encoder angle", 0.0, -inf, inf});
    info.variables.push_back({"tau_ukf", kTauUkf, Causality::Output, "N.m", "UKF joint-torque estimate, eq. (9)-(31)", 0.0});
    info.variables.push_back({"tau_compliance", kTauCompliance, Causality::Output, "N.m", "compliance-model torque, eq. (3)-(8)", 0.0});
    info.variables.push_back({"omega_m", kOmegaM, Causality::Output, "rad/s", "UKF motor-speed estimate", 0.0});
    info.variables.push_back({"dtheta_f", kDthetaF, Causality::Output, "rad", "flexspline torsion, eq. (4)", 0.0});
    info.variables.push_back({"tau_ukf_std", kTauUkfStd, Causality::Output, "N.m", "standard deviation of tau_ukf from the UKF covariance", 0.0});
    info.variables.push_back({"tau_hat", kTauHat, Causality::Output, "N.m", "best causal joint-torque estimate: the joint-state filter (two-mass Kalman filter on the raw encoder angles, driven by the current; beyond the paper)", 0.0});
    info.variables.push_back({"tau_hat_std", kTauHatStd, Causality::Output, "N.m", "standard deviation of tau_hat from the joint-state filter's covariance", 0.0});
    info.create = [] { return std::unique_ptr<Model>(new EstimatorModel()); };
    return info;
}

}  // namespace

const ModelInfo& this_model() {
    static const ModelInfo info = make_info();
    return info;
}

}  // namespace hdjoint::fmu
