// Beyond the paper: the motor current lags the encoders by i_delay; the
// estimator delays the angles by n = round(i_delay/Ts) samples to match.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "compliance_model.h"
#include "parameters.h"
#include "torque_estimator.h"

namespace hdjoint {
namespace {

// A moving, loaded joint as the encoders and a current sensor see it at
// sample k (no delay).
EstimatorInputs joint_at(int k, const Parameters& p) {
    const double t = k * p.Ts;
    const double theta_l = 0.4 * std::sin(2.0 * t) + 0.1 * std::sin(13.0 * t);
    const double tau = 4.0 * std::sin(3.0 * t) + 1.0;
    return {tau / (p.N * p.Kt) + 0.3 * std::sin(9.0 * t), p.N * (theta_l + tau / p.Kf), theta_l};
}

TEST(EffectsDelay, SamplesAreRounded) {
    Parameters p;
    EXPECT_EQ(delay_samples(p), 0);
    p.i_delay = 3.4e-3;
    EXPECT_EQ(delay_samples(p), 3);
    p.i_delay = 3.6e-3;
    EXPECT_EQ(delay_samples(p), 4);
    p.i_delay = 0.128;  // 128 samples of 1 ms: the most (beyond the table's 0.1 s range anyway)
    EXPECT_EQ(delay_samples(p), 128);
}

TEST(EffectsDelay, ValidateLimitsTheDelayTo128Samples) {
    Parameters p;
    p.i_delay = 0.05;
    p.Ts = 1e-4;  // 500 samples
    const auto msg = validate(p, true, false);
    ASSERT_TRUE(msg.has_value());
    EXPECT_NE(msg->find("i_delay"), std::string::npos) << *msg;
    EXPECT_NE(msg->find("500 samples"), std::string::npos) << *msg;
    EXPECT_NE(msg->find("128"), std::string::npos) << *msg;
    EXPECT_FALSE(validate(p, false, true).has_value());  // the joint has no such parameter
    p.Ts = 1e-3;  // 50 samples
    EXPECT_FALSE(validate(p, true, false).has_value());
}

// A current delayed by n samples behind the angles, estimated with
// i_delay = n*Ts, gives exactly the outputs of the undelayed recording,
// n samples later -- with every other estimator effect on too.
TEST(EffectsDelay, OutputsAreTheUndelayedOnesShiftedByNSamples) {
    for (int n : {1, 7, 128}) {
        Parameters base;
        base.hys_H = 0.2;
        base.backlash = 5e-5;
        base.Fs = 0.01;
        base.Fc_drift = 0.002;
        base.cog_a = 0.003;
        base.ke_m1_a = 1e-5;
        Parameters delayed = base;
        delayed.i_delay = n * base.Ts;
        ASSERT_EQ(delay_samples(delayed), n);
        TorqueEstimator reference(base), estimator(delayed);
        std::vector<EstimatorOutputs> expected;
        for (int k = 0; k < 600 + n; ++k) {
            const EstimatorInputs now = joint_at(k, base);
            ASSERT_EQ(reference.step(now), EstimatorStatus::Ok);
            expected.push_back(reference.outputs());
            // The current sensor shows the current of n samples ago.
            EstimatorInputs sensed = now;
            sensed.i_m = joint_at(k - n, base).i_m;
            ASSERT_EQ(estimator.step(sensed), EstimatorStatus::Ok);
            if (k < n) {
                EXPECT_EQ(estimator.samples(), 0);  // the delay line fills
                continue;
            }
            const EstimatorOutputs& a = estimator.outputs();
            const EstimatorOutputs& b = expected[k - n];
            ASSERT_EQ(a.tau_ukf, b.tau_ukf) << "n = " << n << ", k = " << k;
            ASSERT_EQ(a.tau_compliance, b.tau_compliance);
            ASSERT_EQ(a.omega_m, b.omega_m);
            ASSERT_EQ(a.dtheta_f, b.dtheta_f);
            ASSERT_EQ(a.tau_ukf_std, b.tau_ukf_std);
            ASSERT_EQ(a.hysteresis_torque, b.hysteresis_torque);
        }
    }
}

// While the delay line fills, the outputs show the compliance model on the
// first angles and the UKF waits.
TEST(EffectsDelay, WarmUpShowsTheComplianceModelOnTheFirstAngles) {
    Parameters p;
    p.i_delay = 5e-3;
    TorqueEstimator e(p);
    ComplianceModel first(Parameters{});
    const EstimatorInputs in0 = joint_at(0, p);
    const ComplianceSample c0 = first.step(in0.i_m, in0.theta_m, in0.theta_l);
    ASSERT_EQ(e.step(in0), EstimatorStatus::Ok);
    EXPECT_EQ(e.outputs().tau_compliance, c0.tau);
    EXPECT_EQ(e.outputs().tau_ukf, c0.tau);
    EXPECT_EQ(e.outputs().tau_ukf_std, p.ukf_p0_tau);
    for (int k = 1; k < 5; ++k) {
        EstimatorInputs in = joint_at(k, p);
        in.i_m = in0.i_m;
        ASSERT_EQ(e.step(in), EstimatorStatus::Ok);
        EXPECT_EQ(e.outputs().tau_compliance, c0.tau) << k;  // same current, first angles
        EXPECT_EQ(e.samples(), 0);
    }
    ASSERT_EQ(e.step(joint_at(5, p)), EstimatorStatus::Ok);
    EXPECT_EQ(e.samples(), 1);
}

TEST(EffectsDelay, ComplianceModelStateRoundTripsThroughTheDelayLine) {
    Parameters p;
    p.i_delay = 9e-3;
    p.hys_H = 0.3;
    for (int stop : {0, 4, 9, 10, 200, 257}) {
        ComplianceModel a(p);
        for (int k = 0; k < stop; ++k) a.step(joint_at(k, p).i_m, joint_at(k, p).theta_m, joint_at(k, p).theta_l);
        std::vector<double> saved;
        a.save(&saved);
        ASSERT_EQ(saved.size(), 4u + 2u * 9u);
        ComplianceModel b(p);
        std::size_t cursor = 0;
        ASSERT_TRUE(b.load(saved, &cursor));
        EXPECT_EQ(cursor, saved.size());
        std::vector<double> again;
        b.save(&again);
        EXPECT_EQ(again, saved);
        for (int k = stop; k < stop + 300; ++k) {
            const EstimatorInputs in = joint_at(k, p);
            const ComplianceSample x = a.step(in.i_m, in.theta_m, in.theta_l);
            const ComplianceSample y = b.step(in.i_m, in.theta_m, in.theta_l);
            ASSERT_EQ(x.tau, y.tau) << stop << " " << k;
            ASSERT_EQ(x.theta_m, y.theta_m);
        }
    }
}

// Off (i_delay below half a sample) is the paper's estimator bit for bit.
TEST(EffectsDelay, UnderHalfASampleIsOff) {
    Parameters p;
    p.i_delay = 0.49e-3;
    const Parameters paper;
    TorqueEstimator a(paper), b(p);
    for (int k = 0; k < 300; ++k) {
        a.step(joint_at(k, p));
        b.step(joint_at(k, p));
        ASSERT_EQ(a.save_state(), b.save_state());
    }
}

}  // namespace
}  // namespace hdjoint
