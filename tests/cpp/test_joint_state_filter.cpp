// The joint-state filter (joint_state_filter.h): the analytic Jacobian
// against differences, static balance with an unknown link load, state
// save/restore, recovery from a broken covariance, and the smoother.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "joint_plant.h"
#include "joint_state_filter.h"
#include "parameters.h"
#include "torque_estimator.h"

namespace hdjoint {
namespace {

TEST(JointStateFilter, JacobianMatchesCentralDifferences) {
    Parameters p;
    p.ke_m1_a = 3e-6;  // extra terms on, so their derivatives are checked too
    p.cog_a = 0.002;
    p.wg_load = 1.0;
    JointSystemModel m;
    m.p = p;
    m.h = p.Ts;
    JointState x;
    x << 0.3, 0.2, 2.5e-4, 0.01, 0.7, 2.0, 0.05, 0.02, 0.015;
    const JointInput u{0.4, 0.0, 0.0};
    JointState dx;
    JointCovariance J;
    ASSERT_TRUE(m.derivative(x, u, &dx, &J));
    const double steps[kJointStates] = {1e-7, 1e-5, 1e-9, 1e-5, 1e-5, 1e-5, 1e-6, 1e-5, 1e-6};
    for (int c = 0; c < kJointStates; ++c) {
        JointState hi = x, lo = x, dhi, dlo;
        JointCovariance unused;
        hi(c) += steps[c];
        lo(c) -= steps[c];
        ASSERT_TRUE(m.derivative(hi, u, &dhi, &unused));
        ASSERT_TRUE(m.derivative(lo, u, &dlo, &unused));
        const JointState fd = (dhi - dlo) / (2.0 * steps[c]);
        for (int r = 0; r < kJointStates; ++r)
            EXPECT_NEAR(J(r, c), fd(r), 1e-5 * (1.0 + std::fabs(fd(r)))) << r << "," << c;
    }
}

TEST(JointStateFilter, FindsTheStaticLoadTheLinkModelDoesNotKnow) {
    // The joint at rest holds gravity plus an external torque of 1.5 N.m; the
    // filter's link model knows neither the torque nor the right mgl.
    Parameters p;
    p.motor_counts = p.link_counts = 0.0;
    p.theta_l0 = 0.4;
    JointPlant plant(p);
    const double tau_ext = 1.5;
    ASSERT_TRUE(plant.initialize(tau_ext));
    double tau_true = 0.0;
    ASSERT_TRUE(plant.joint_torque(plant.state(), &tau_true));
    const double i_hold = tau_true / (p.N * p.Kt);  // at rest the motor holds tau/N (no friction at rest)
    Parameters q = p;
    q.wg_load = 1.0;
    q.mgl = 0.9 * p.mgl;
    q.jsf_r_theta_m = 1e-6;
    q.jsf_r_theta_l = 1e-8;
    JointStateFilter f(q);
    for (int k = 0; k < 3000; ++k) {
        ASSERT_TRUE(plant.advance(1e-3, {i_hold, tau_ext}));
        const PlantOutputs o = plant.outputs();
        f.step(o.theta_m, o.theta_l, {i_hold, 0.0, k * 1e-3});
    }
    EXPECT_NEAR(f.output().tau, tau_true, 1e-3 * std::fabs(tau_true));
    // The load state took what the link model misses: tau_ext and the 10 % of gravity.
    EXPECT_NEAR(f.output().load, tau_true - q.mgl * std::sin(plant.state()(2)), 0.02);
    EXPECT_GT(f.output().tau_std, 0.0);
}

std::vector<EstimatorInputs> moving_joint(const Parameters& p, int n) {
    JointPlant plant(p);
    EXPECT_TRUE(plant.initialize(0.0));
    std::vector<EstimatorInputs> inputs;
    for (int k = 0; k < n; ++k) {
        const double i = 0.6 * std::sin(2.0 * M_PI * 1.3 * k * 1e-3) + 0.3;
        EXPECT_TRUE(plant.advance(1e-3, {i, 0.5 * std::sin(k * 1e-3)}));
        inputs.push_back({i, plant.outputs().theta_m, plant.outputs().theta_l});
    }
    return inputs;
}

TEST(JointStateFilter, SaveRestoreIsExact) {
    const Parameters p;
    const std::vector<EstimatorInputs> inputs = moving_joint(p, 600);
    for (int split : {0, 1, 300}) {
        TorqueEstimator a(p);
        for (int k = 0; k < split; ++k) a.step(inputs[k]);
        const std::vector<double> saved = a.save_state();
        TorqueEstimator b(p);
        ASSERT_TRUE(b.load_state(saved));
        for (int k = split; k < 600; ++k) {
            a.step(inputs[k]);
            b.step(inputs[k]);
        }
        EXPECT_EQ(a.outputs().tau_hat, b.outputs().tau_hat) << split;
        EXPECT_EQ(a.outputs().tau_hat_std, b.outputs().tau_hat_std) << split;
        EXPECT_EQ(a.save_state(), b.save_state()) << split;
    }
    // A truncated joint-filter state is refused.
    TorqueEstimator a(p);
    a.step(inputs[0]);
    std::vector<double> saved = a.save_state();
    saved.pop_back();
    TorqueEstimator b(p);
    EXPECT_FALSE(b.load_state(saved));
}

TEST(JointStateFilter, RecoversFromABrokenCovariance) {
    const Parameters p;
    const std::vector<EstimatorInputs> inputs = moving_joint(p, 800);
    auto held = [&](int k) { return JointInput{inputs[k].i_m, 0.0, k * 1e-3}; };
    JointStateFilter a(p);
    for (int k = 0; k < 400; ++k) a.step(inputs[k].theta_m, inputs[k].theta_l, held(k));
    // Break the filter's covariance (what a failed factorisation leaves): NaN.
    // Planted through the filter's own flat block: load_state() refuses a NaN,
    // as the FMU does.
    std::vector<double> saved;
    a.save(&saved);
    saved[1 + kJointStates + 7] = std::numeric_limits<double>::quiet_NaN();
    JointStateFilter b(p);
    std::size_t cursor = 0;
    ASSERT_TRUE(b.load(saved, &cursor));
    EXPECT_EQ(b.step(inputs[400].theta_m, inputs[400].theta_l, held(400)), FilterStatus::CovarianceReset);
    for (int k = 401; k < 800; ++k) b.step(inputs[k].theta_m, inputs[k].theta_l, held(k));
    EXPECT_TRUE(std::isfinite(b.output().tau));
    for (int k = 400; k < 800; ++k) a.step(inputs[k].theta_m, inputs[k].theta_l, held(k));
    EXPECT_NEAR(b.output().tau, a.output().tau, 0.01);
}

TEST(JointStateFilter, UnreadableSamplesArePredictedOverWithGrowingDeviation) {
    const Parameters p;
    const std::vector<EstimatorInputs> inputs = moving_joint(p, 700);
    JointStateFilter f(p), clean(p);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    double last_std = 0.0;
    for (int k = 0; k < 700; ++k) {
        const EstimatorInputs& in = inputs[k];
        const JointInput u{in.i_m, 0.0, k * 1e-3};
        clean.step(in.theta_m, in.theta_l, u);
        if (k >= 400 && k < 410) {
            // Ten unreadable samples: no update, the filter only predicts and says so.
            EXPECT_EQ(f.step(nan, in.theta_l, u), FilterStatus::SampleRejected) << k;
            EXPECT_TRUE(f.state().allFinite());
            EXPECT_GT(f.output().tau_std, last_std) << k;
        } else {
            EXPECT_NE(f.step(in.theta_m, in.theta_l, u), FilterStatus::SampleRejected) << k;
        }
        last_std = f.output().tau_std;
    }
    EXPECT_NEAR(f.output().tau, clean.output().tau, 1e-3);
}

TEST(JointStateFilter, OneOutlierCurrentIsRejectedVisiblyAndTheFilterRecovers) {
    // The audit's case (issue 12): one sample of i_m = 1e6 A used to freeze
    // tau_hat with tau_hat_std = 0 and no message. With a current sensor
    // that reads it (10 x i_peak >= 1e6 A) it is the joint-state filter's
    // outlier; with the default sensor it is gated before either filter sees
    // it (issue 56).
    const std::vector<EstimatorInputs> inputs = moving_joint(Parameters{}, 900);
    const double current = 1e6;
    for (const double i_peak : {1e5, Parameters{}.i_peak}) {
        Parameters p;
        p.i_peak = i_peak;
        const bool gated = current > kWildCurrentMultiple * p.i_peak;
        TorqueEstimator a(p), clean(p);
        int rejected = 0;
        for (int k = 0; k < 900; ++k) {
            EstimatorInputs in = inputs[k];
            if (k == 400) in.i_m = current;
            clean.step(inputs[k]);
            std::string message;
            const EstimatorStatus s = a.step(in, &message);
            ASSERT_TRUE(recoverable(s)) << k << ": " << message;
            if (s == EstimatorStatus::SampleRejected || s == EstimatorStatus::ReadingGated) {
                ++rejected;
                EXPECT_NE(message.find(gated ? "no sensor could produce" : "outlier"), std::string::npos) << message;
                EXPECT_EQ(s == EstimatorStatus::ReadingGated, gated) << i_peak;
            }
            EXPECT_GT(a.outputs().tau_hat_std, 0.0) << k;
            EXPECT_TRUE(std::isfinite(a.outputs().tau_hat)) << k;
        }
        EXPECT_EQ(rejected, 1) << i_peak;
        EXPECT_NEAR(a.outputs().tau_hat, clean.outputs().tau_hat, 1e-3) << i_peak;
        EXPECT_NEAR(a.outputs().tau_hat_std, clean.outputs().tau_hat_std, 1e-6) << i_peak;
    }
}

TEST(JointStateFilter, ARestoredFilterRejectsAnOutlierAsTheOriginalDoes) {
    // A rejected sample starts over from the state before it: after load(),
    // the loaded one (not the fresh filter's). The outlier current is held
    // from the last sample before the save, so the first one after is rejected.
    const Parameters p;
    const std::vector<EstimatorInputs> inputs = moving_joint(p, 500);
    auto held = [&](int k) { return JointInput{k == 399 ? 1e6 : inputs[k].i_m, 0.0, k * 1e-3}; };
    JointStateFilter a(p);
    for (int k = 0; k < 400; ++k) a.step(inputs[k].theta_m, inputs[k].theta_l, held(k));
    std::vector<double> saved;
    a.save(&saved);
    JointStateFilter b(p);
    std::size_t cursor = 0;
    ASSERT_TRUE(b.load(saved, &cursor));
    for (int k = 400; k < 500; ++k) {
        const FilterStatus sa = a.step(inputs[k].theta_m, inputs[k].theta_l, held(k));
        const FilterStatus sb = b.step(inputs[k].theta_m, inputs[k].theta_l, held(k));
        if (k == 400) {
            EXPECT_EQ(sa, FilterStatus::SampleRejected);
        }
        ASSERT_EQ(sa, sb) << k;
        ASSERT_EQ(a.output().tau, b.output().tau) << k;
        ASSERT_EQ(a.output().tau_std, b.output().tau_std) << k;
    }
}

TEST(JointStateFilter, SmootherEndsOnTheFilterAndBeatsItInBetween) {
    Parameters p;
    JointPlant plant(p);
    ASSERT_TRUE(plant.initialize(0.0));
    p.wg_load = 1.0;  // the joint's wave generator carries tau/N
    JointStateFilter f(p);
    std::vector<JointFilterRecord> records;
    std::vector<double> filtered, filtered_std, truth;
    for (int k = 0; k < 1500; ++k) {
        const double i = 0.6 * std::sin(2.0 * M_PI * 1.3 * k * 1e-3) + 0.3;
        const PlantOutputs o = plant.outputs();
        f.step(o.theta_m, o.theta_l, {i, 0.0, k * 1e-3});
        records.push_back(f.record());
        filtered.push_back(f.output().tau);
        filtered_std.push_back(f.output().tau_std);
        truth.push_back(o.tau_joint);
        ASSERT_TRUE(plant.advance(1e-3, {i, 0.5 * std::sin(k * 1e-3)}));
    }
    const SmoothedTorque s = smooth_joint_states(records, p);
    ASSERT_EQ(s.tau.size(), records.size());
    EXPECT_EQ(s.tau.back(), filtered.back());
    double err_f = 0.0, err_s = 0.0;
    for (std::size_t k = 100; k < records.size(); ++k) {
        // It sees more data: its uncertainty is never above the filter's.
        EXPECT_LE(s.tau_std[k], filtered_std[k] * (1.0 + 1e-9)) << k;
        err_f += (filtered[k] - truth[k]) * (filtered[k] - truth[k]);
        err_s += (s.tau[k] - truth[k]) * (s.tau[k] - truth[k]);
    }
    EXPECT_LT(err_s, 0.7 * err_f);
}

}  // namespace
}  // namespace hdjoint
