// The joint and the estimator together: both implement CONTRACT.md's sign
// conventions, so the estimator's compliance model reads the plant's joint
// torque back from the plant's encoder angles.
#include <gtest/gtest.h>

#include <cmath>

#include "joint_plant.h"
#include "parameters.h"
#include "torque_estimator.h"

namespace hdjoint {
namespace {

constexpr double kPi = 3.141592653589793;

EstimatorInputs read(const JointPlant& j, double i_m) {
    const PlantOutputs o = j.outputs();
    EstimatorInputs in;
    in.i_m = i_m;
    in.theta_m = o.theta_m;
    in.theta_l = o.theta_l;
    return in;
}

TEST(PlantAndEstimator, StaticHoldIsEstimatedExactly) {
    for (double tau_ext : {3.0, -2.0}) {
        Parameters p;  // default kinematic error, compliant wave generator, gravity
        p.motor_counts = p.link_counts = 0.0;
        p.theta_l0 = 0.2;
        JointPlant j(p);
        ASSERT_TRUE(j.initialize(tau_ext));
        const double tau = p.mgl * std::sin(p.theta_l0) + tau_ext;
        const double i_hold = tau / p.N / p.Kt;  // Kt*i = tau/N: the estimator's tau_w is exact
        TorqueEstimator est(p);
        for (int k = 0; k < 500; ++k) {
            ASSERT_EQ(est.step(read(j, i_hold)), EstimatorStatus::Ok);
            ASSERT_TRUE(j.advance(p.Ts, PlantInputs{i_hold, tau_ext}));
        }
        EXPECT_NEAR(est.outputs().tau_compliance, tau, 1e-6) << tau_ext;
        EXPECT_NEAR(est.outputs().tau_ukf, tau, 1e-4 * (1.0 + std::fabs(tau))) << tau_ext;
        EXPECT_NEAR(est.outputs().omega_m, 0.0, 1e-3);
    }
}

TEST(PlantAndEstimator, StaticHoldThroughQuantisedEncoders) {
    Parameters p;  // 4096-count motor and 19-bit link encoders
    p.theta_l0 = 0.2;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(3.0));
    const double tau = p.mgl * std::sin(p.theta_l0) + 3.0;
    const double i_hold = tau / p.N / p.Kt;
    TorqueEstimator est(p);
    for (int k = 0; k < 500; ++k) {
        ASSERT_EQ(est.step(read(j, i_hold)), EstimatorStatus::Ok);
        ASSERT_TRUE(j.advance(p.Ts, PlantInputs{i_hold, 3.0}));
    }
    // One motor count is 2*pi/4096/N = 1.5e-5 rad of torsion, one link count
    // 1.2e-5 rad: with Kf = 1e4 at most ~0.3 N.m together.
    EXPECT_NEAR(est.outputs().tau_ukf, tau, 0.35);
}

TEST(PlantAndEstimator, ComplianceModelReadsTheMovingPlantsTorque) {
    // A stiff wave generator removes the one approximation of the paper's
    // compliance model (tau_w = Kt*i_m instead of tau_f/N): what is left must
    // agree exactly with the plant while the joint swings through its range.
    Parameters p;
    p.Kw = 1e9;
    p.Bl = 2.0;
    p.motor_counts = p.link_counts = 0.0;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    TorqueEstimator est(p);
    double sum_tau2 = 0.0, sum_err2 = 0.0, max_compliance_err = 0.0, max_tau = 0.0;
    int n = 0;
    for (int k = 0; k < 4000; ++k) {
        const double i_m = std::sin(2.0 * kPi * 0.5 * k * p.Ts);
        ASSERT_TRUE(recoverable(est.step(read(j, i_m))));
        const double tau = j.outputs().tau_joint;
        max_compliance_err = std::max(max_compliance_err, std::fabs(est.outputs().tau_compliance - tau));
        max_tau = std::max(max_tau, std::fabs(tau));
        if (k >= 1000) {
            sum_tau2 += tau * tau;
            sum_err2 += std::pow(est.outputs().tau_ukf - tau, 2);
            ++n;
        }
        ASSERT_TRUE(j.advance(p.Ts, PlantInputs{i_m, 0.0}));
    }
    EXPECT_GT(max_tau, 3.0);
    EXPECT_LT(max_compliance_err, 1e-6 * max_tau);
    // The UKF lags (random-walk torque model) but follows with the right sign.
    EXPECT_LT(std::sqrt(sum_err2 / n), 0.4 * std::sqrt(sum_tau2 / n));
}

}  // namespace
}  // namespace hdjoint
