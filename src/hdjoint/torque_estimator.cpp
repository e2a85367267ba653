#include "torque_estimator.h"

#include <cmath>
#include <sstream>

#include "friction.h"
#include "transmission.h"

namespace hdjoint {

namespace {
// std_nis_time: a deviation scaled by the running mean m of NIS/2 (2
// measurements each), never below the filter's own.
double consistent(double std, double nis, double Ts, double time, double* mean) {
    if (time <= 0.0) return std;
    if (std::isfinite(nis)) *mean += std::min(1.0, Ts / time) * (0.5 * nis - *mean);
    return std * std::sqrt(std::max(1.0, *mean));
}

constexpr double kTwoPi = 6.283185307179586;

std::string describe_input(const EstimatorInputs& in) {
    std::ostringstream s;
    s.precision(17);
    if (!std::isfinite(in.i_m)) s << "input i_m = " << in.i_m << " is not finite";
    else if (!std::isfinite(in.theta_m)) s << "input theta_m = " << in.theta_m << " is not finite";
    else s << "input theta_l = " << in.theta_l << " is not finite";
    return s.str();
}
}  // namespace

HDJ_DEFINE_SIGNAL_TABLE(estimator_signals, EstimatorInputs, EstimatorOutputs, HDJ_ESTIMATOR_SIGNALS)

TorqueEstimator::TorqueEstimator(const Parameters& p, double start_time)
    : p_(p), system_(p, p.Ts), measurement_(p), compliance_(p), joint_(p), clock_(start_time, p.Ts) {
    Q_.diagonal() << p.ukf_q_omega * p.ukf_q_omega, p.ukf_q_tau * p.ukf_q_tau;
    R_.diagonal() << p.ukf_r_omega * p.ukf_r_omega, p.ukf_r_torsion * p.ukf_r_torsion;
    Matrix<2> P0 = Matrix<2>::Zero();
    P0.diagonal() << p.ukf_p0_omega * p.ukf_p0_omega, p.ukf_p0_tau * p.ukf_p0_tau;
    ukf_ = UnscentedKalmanFilter<2>(merwe_weights<2>(p.ukf_alpha, p.ukf_beta, p.ukf_kappa),
                                    Vector<2>::Zero(), P0);
}

std::string TorqueEstimator::wild(const EstimatorInputs& in) const {
    if (!std::isfinite(in.i_m) || !std::isfinite(in.theta_m) || !std::isfinite(in.theta_l)) return describe_input(in);
    const double i_max = kWildCurrentMultiple * p_.i_peak;
    if (std::fabs(in.i_m) > i_max) {
        std::ostringstream s;
        s.precision(6);
        s << "input i_m = " << in.i_m << " A is beyond " << kWildCurrentMultiple << " x i_peak = " << i_max
          << " A, more than the current sensor reads";
        return s.str();
    }
    if (!has_accepted_) return "";
    // The time since the last accepted reading, and a late reading's age.
    const double time = p_.Ts * (static_cast<double>(since_accepted_) + kMaxReadingAge);
    struct Channel {
        const char* name;
        const char* speed_name;
        double now, before, speed, counts;
    };
    const Channel channels[] = {
        {"theta_m", "omega_m_max", in.theta_m, accepted_.theta_m, p_.omega_m_max, p_.motor_counts},
        {"theta_l", "omega_m_max/N", in.theta_l, accepted_.theta_l, p_.omega_m_max / p_.N, p_.link_counts}};
    for (const Channel& c : channels) {
        const double bound = c.speed * time + (c.counts > 0.0 ? kJumpCounts * kTwoPi / c.counts : 0.0);
        const double moved = std::fabs(c.now - c.before);
        if (!(moved <= bound)) {
            std::ostringstream s;
            s.precision(6);
            s << "input " << c.name << " moved " << moved << " rad in " << since_accepted_
              << " sample(s) since the last accepted reading, more than the joint can (at most " << bound
              << " rad: " << c.speed_name << " = " << c.speed << " rad/s, plus "
              << kJumpCounts << " counts)";
            return s.str();
        }
    }
    return "";
}

EstimatorStatus TorqueEstimator::step(const EstimatorInputs& in, std::string* message, bool reading, double age) {
    if (has_accepted_) ++since_accepted_;
    const long k = samples_;
    std::string why = wild(in);
    if (why.empty()) {
        const EstimatorInputs before = accepted_;
        const bool had = has_accepted_;
        const long since = since_accepted_;
        accepted_ = in;
        has_accepted_ = true;
        since_accepted_ = 0;
        const EstimatorStatus s = sample(in, message, reading, age);
        if (s != EstimatorStatus::ReadingGated) {
            gated_run_ = 0;
            return s;
        }
        // A torsion no torque explains (sample): not a reading to hold on to.
        accepted_ = before;
        has_accepted_ = had;
        since_accepted_ = since;
        if (message) why = *message;
    } else if (has_accepted_) {
        // Treated as missing: the last accepted reading is held in its place, so
        // both filters predict over the sample (before any, nothing runs).
        const EstimatorStatus s = sample(accepted_, message, false, age);
        if (!recoverable(s)) return s;
    }
    ++gated_;
    // Said once for a run of them: the samples that follow at once are counted (ReadingGated), not said again.
    const bool first = ++gated_run_ == 1;
    if (message) message->clear();
    if (message && first) {
        std::ostringstream s;
        s.precision(6);
        s << "sample " << k << ": a reading no sensor could produce (" << why
          << "); treated as missing, as is any that follows at once (counted, not said again): both filters "
             "predicted over it, tau_ukf_std and tau_hat_std grow";
        *message = s.str();
    }
    return EstimatorStatus::ReadingGated;
}

EstimatorStatus TorqueEstimator::sample(const EstimatorInputs& in, std::string* message, bool reading, double age) {
    if (!std::isfinite(in.i_m) || !std::isfinite(in.theta_m) || !std::isfinite(in.theta_l)) {
        if (message) *message = describe_input(in);
        return EstimatorStatus::InvalidInput;
    }
    const ComplianceSample c = compliance_.step(in.i_m, in.theta_m, in.theta_l);
    if (!c.valid) {
        if (message) {
            std::ostringstream s;
            s.precision(17);
            s << "singular torsion: dtheta_f = " << c.dtheta_f << " rad gives |Cf*Kf*dtheta_f| = "
              << std::fabs(p_.Cf * p_.Kf * backlash_deadzone(c.dtheta_f, p_))
              << " >= pi/2 (theta_m = " << c.theta_m << ", theta_l = " << c.theta_l
              << ")";
            if (samples_ == 0 || singular_run_ >= max_singular_samples())
                s << "; check N, a0 (encoder offsets), Kf and Cf";
            if (singular_run_ > 0 && singular_run_ >= max_singular_samples())
                s << " (no torque has explained the torsion for " << singular_run_ << " samples, since sample "
                  << samples_ - singular_run_ << ")";
            *message = s.str();
        }
        // Once the filters run, a torsion no torque explains is no reading the
        // joint could produce (a glitch): predicted over, on the last valid
        // compliance sample, until it has lasted kMaxSingularTime.
        if (samples_ > 0 && singular_run_ < max_singular_samples()) {
            ++singular_run_;
            ComplianceSample held;
            held.valid = true;
            held.theta_m = previous_theta_m_;
            held.tau = out_.tau_compliance;
            held.dtheta_f = out_.dtheta_f;
            held.z = out_.hysteresis_torque;
            predict_held(in, held, nullptr);
            return EstimatorStatus::ReadingGated;
        }
        return EstimatorStatus::SingularTorsion;
    }
    singular_run_ = 0;
    if (!c.ready) {
        // The delay line is filling: no angles yet for this current. Show the
        // compliance model on the first angles; the filter waits.
        show_compliance(c.tau, c.dtheta_f);
        return EstimatorStatus::Ok;
    }

    if (!reading && samples_ > 0) return predict_held(in, c, message);

    FilterStatus predicted = FilterStatus::Ok;
    double speed = 0.0;  // the first sample has no previous angle: speed 0
    if (samples_ == 0) {
        ukf_.state() << 0.0, c.tau;
        ukf_.covariance() = ukf_.initial_covariance();
    } else {
        predicted = ukf_.predict(system_, previous_u_, Q_);
        // Over the samples predicted without a reading since the last one too.
        speed = (c.theta_m - previous_theta_m_) / (p_.Ts * static_cast<double>(1 + samples_held_));
    }
    samples_held_ = 0;
    Vector<2> z;
    z << speed, c.torsion;
    const auto update = ukf_.update(measurement_, z, R_);

    const Vector<2>& x = ukf_.state();
    out_.tau_ukf = x(1);
    out_.omega_m = x(0);
    out_.tau_ukf_std = consistent(std::sqrt(std::max(ukf_.covariance()(1, 1), 0.0)), update.nis, p_.Ts,
                                  p_.std_nis_time, &nis_mean_ukf_);
    out_.tau_compliance = c.tau;
    out_.dtheta_f = c.dtheta_f;
    out_.nis = update.nis;
    out_.hysteresis_torque = c.z;
    previous_theta_m_ = c.theta_m;
    // The joint-state filter on the same (delayed) angles, current and hysteresis torque.
    const double t = static_cast<double>(samples_) * p_.Ts;
    // (The compliance model's delay line matches the current with earlier angles: their age is the row's.)
    const FilterStatus joint = joint_.step(c.theta_m, c.theta_l, {in.i_m, c.z, t}, age);
    out_.tau_hat = joint_.output().tau;
    out_.tau_hat_std = consistent(joint_.output().tau_std, joint_.output().nis, p_.Ts, p_.std_nis_time, &nis_mean_hat_);
    out_.tau_load = joint_.output().load;
    // eq. (2)'s input, with cogging, Stribeck friction and the drift when they are on.
    previous_u_ = motor_torque(in.i_m, c.theta_m, t, p_) - coulomb_friction(x(0), p_, friction_drift_scale(t, p_));
    ++samples_;

    // Report the worst thing the filter had to do on this sample.
    const FilterStatus worst = std::max(std::max(predicted, update.status), joint);
    switch (worst) {
        case FilterStatus::Ok: return EstimatorStatus::Ok;
        case FilterStatus::CovarianceRepaired:
            if (message) *message = "UKF covariance was not positive definite; repaired with diagonal jitter";
            return EstimatorStatus::CovarianceRepaired;
        case FilterStatus::CovarianceReset:
            if (message) *message = "UKF covariance could not be factorised; reset to the initial covariance";
            return EstimatorStatus::CovarianceReset;
        case FilterStatus::UpdateSkipped:
            if (message) *message = "UKF innovation covariance is singular; measurement update skipped";
            return EstimatorStatus::UpdateSkipped;
        case FilterStatus::SampleRejected:
            if (message) {
                std::ostringstream s;
                s.precision(6);
                s << "joint-state filter: sample " << samples_ - 1 << " rejected as an outlier (innovation NIS "
                  << joint_.output().nis << " > " << kOutlierGate << ", or no torque explains it; i_m = " << in.i_m
                  << " A); predicted over it, tau_hat_std grows";
                *message = s.str();
            }
            return EstimatorStatus::SampleRejected;
    }
    return EstimatorStatus::Ok;
}

EstimatorStatus TorqueEstimator::predict_held(const EstimatorInputs& in, const ComplianceSample& c,
                                              std::string* message) {
    const FilterStatus predicted = ukf_.predict(system_, previous_u_, Q_);
    const Vector<2>& x = ukf_.state();
    out_.tau_ukf = x(1);
    out_.omega_m = x(0);
    // The deviations widen with the prediction (the NIS means of std_nis_time hold: no innovation).
    out_.tau_ukf_std = std::sqrt(std::max(ukf_.covariance()(1, 1), 0.0)) *
                       (p_.std_nis_time > 0.0 ? std::sqrt(std::max(1.0, nis_mean_ukf_)) : 1.0);
    out_.tau_compliance = c.tau;
    out_.dtheta_f = c.dtheta_f;
    out_.nis = 0.0;
    out_.hysteresis_torque = c.z;
    const double t = static_cast<double>(samples_) * p_.Ts;
    joint_.predict_without_reading({in.i_m, c.z, t});
    out_.tau_hat = joint_.output().tau;
    out_.tau_hat_std = joint_.output().tau_std *
                       (p_.std_nis_time > 0.0 ? std::sqrt(std::max(1.0, nis_mean_hat_)) : 1.0);
    out_.tau_load = joint_.output().load;
    previous_u_ = motor_torque(in.i_m, c.theta_m, t, p_) - coulomb_friction(x(0), p_, friction_drift_scale(t, p_));
    ++samples_;
    ++samples_held_;
    (void)predicted;  // a reset covariance (non-finite P) is reported by the next reading's update
    if (message) {
        std::ostringstream s;
        s.precision(6);
        s << "gap: sample " << samples_ - 1 << " has no new reading (the inputs were held over "
          << samples_held_ + 1 << " samples of Ts = " << p_.Ts
          << " s); both filters predicted over it, tau_ukf_std and tau_hat_std grow";
        *message = s.str();
    }
    return EstimatorStatus::ReadingsHeld;
}

void TorqueEstimator::show_start(const EstimatorInputs& in) {
    const ComplianceEstimate c = compliance_estimate(in.i_m, in.theta_m, in.theta_l, p_);
    show_compliance(c.valid ? c.tau : 0.0, c.valid ? c.dtheta_f : 0.0);
}

void TorqueEstimator::show_compliance(double tau, double dtheta_f) {
    out_ = EstimatorOutputs{};
    out_.tau_ukf = out_.tau_compliance = out_.tau_hat = tau;
    out_.dtheta_f = dtheta_f;
    out_.tau_ukf_std = p_.ukf_p0_tau;
    out_.tau_hat_std = p_.jsf_p0_load;
}

}  // namespace hdjoint
