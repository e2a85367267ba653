#pragma once
// The paper's torque estimator: the compliance model of eq. (3)-(8) and the
// UKF of eq. (9)-(31), run at a fixed sample period on encoder angles and
// motor current; beside them the joint-state filter (tau_hat, beyond the paper).
#include <string>
#include <vector>

#include "compliance_model.h"
#include "joint_state_filter.h"
#include "paper_ukf_models.h"
#include "parameters.h"
#include "ukf.h"

namespace hdjoint {

struct EstimatorInputs {
    double i_m = 0.0;      // A
    double theta_m = 0.0;  // rad
    double theta_l = 0.0;  // rad
};

struct EstimatorOutputs {
    double tau_ukf = 0.0;         // N.m
    double tau_compliance = 0.0;  // N.m
    double omega_m = 0.0;         // rad/s
    double dtheta_f = 0.0;        // rad
    double tau_ukf_std = 0.0;     // N.m
    double nis = 0.0;             // normalised innovation squared of the last update
    double hysteresis_torque = 0.0;  // Dahl hysteresis torque inside tau_compliance, N.m (0 when off)
    double tau_hat = 0.0;         // joint-state filter torque, N.m (beyond the paper)
    double tau_hat_std = 0.0;     // its standard deviation, N.m
    double load = 0.0;            // the filter's link-load state w, N.m
};

enum class EstimatorStatus {
    Ok,
    CovarianceRepaired,  // the UKF repaired an indefinite covariance (can go on)
    CovarianceReset,     // the UKF reset its covariance (can go on)
    UpdateSkipped,       // the measurement update was skipped (can go on)
    SampleRejected,      // the joint-state filter rejected an outlier sample and predicted over it (can go on)
    SingularTorsion,     // |Cf*Kf*dtheta_f| >= pi/2: no torque explains the torsion
    InvalidInput,        // NaN or infinite input
};

// True for statuses after which the estimate is still usable.
inline bool recoverable(EstimatorStatus s) {
    return s != EstimatorStatus::SingularTorsion && s != EstimatorStatus::InvalidInput;
}

class TorqueEstimator {
public:
    explicit TorqueEstimator(const Parameters& p);

    // Process one sample (inputs valid at this sample's time). `message`,
    // when given, names what went wrong for any status but Ok. With i_delay
    // the current is matched with the angles of round(i_delay/Ts) samples
    // before, and the first that many samples only fill the delay line.
    EstimatorStatus step(const EstimatorInputs& in, std::string* message = nullptr);

    const EstimatorOutputs& outputs() const { return out_; }
    const Parameters& parameters() const { return p_; }
    long samples() const { return samples_; }

    // Flat, versioned state for FMU serialisation (parameters excluded).
    std::vector<double> save_state() const;
    bool load_state(const std::vector<double>& data);

    // The joint-state filter (tau_hat): its last sample, for the smoother.
    const JointStateFilter& joint_filter() const { return joint_; }

private:
    Parameters p_;
    PaperSystemModel system_;
    PaperMeasurementModel measurement_;
    Matrix<2> Q_ = Matrix<2>::Zero();
    Matrix<2> R_ = Matrix<2>::Zero();
    UnscentedKalmanFilter<2> ukf_;
    ComplianceModel compliance_;
    JointStateFilter joint_;
    EstimatorOutputs out_;
    double previous_theta_m_ = 0.0;
    double previous_u_ = 0.0;  // Kt*i_m - tau_fm of the previous sample
    // Running means of NIS/2 of the paper UKF and the joint-state filter (std_nis_time).
    double nis_mean_ukf_ = 1.0, nis_mean_hat_ = 1.0;
    long samples_ = 0;
};

}  // namespace hdjoint
