// Saved state restores exactly with every beyond-the-paper effect on: the
// plant's hysteresis and bristle states and its time, the estimator's
// hysteresis and delay line.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "joint_plant.h"
#include "parameters.h"
#include "torque_estimator.h"

namespace hdjoint {
namespace {

Parameters everything_on() {
    Parameters p;
    p.ke_m2_a = 1e-5;
    p.ke_l1_b = -2e-5;
    p.hys_H = 0.3;
    p.backlash = 1e-4;
    p.Fs = 0.01;
    p.Fc_drift = 0.003;
    p.cog_a = 0.004;
    p.i_delay = 3e-3;
    p.Fl = 0.4;
    p.lugre_sigma0 = 2e4;
    p.lugre_sigma1 = 0.02;
    p.bw_A = 5e3;
    p.bw_beta = 2e4;
    p.bw_gamma = 1e4;
    p.thermal_gain = 0.5;
    p.thermal_tc = 0.3;
    return p;
}

PlantInputs drive(int k) { return {1.5 * std::sin(3e-3 * k) + 0.4 * std::sin(0.05 * k), 0.3 * std::sin(1e-3 * k)}; }

TEST(EffectsState, PlantRestoresExactly) {
    const Parameters p = everything_on();
    JointPlant a(p);
    ASSERT_TRUE(a.initialize(0.2));
    for (int k = 0; k < 700; ++k) ASSERT_TRUE(a.advance(1e-3, drive(k)));
    const std::vector<double> saved = a.save_state();
    EXPECT_EQ(saved.size(), 9u);
    EXPECT_NE(saved[6], 0.0);  // the hysteresis and bristle states are alive
    EXPECT_NE(saved[7], 0.0);
    EXPECT_NE(saved[8], 0.0);
    for (int k = 700; k < 1400; ++k) ASSERT_TRUE(a.advance(1e-3, drive(k)));
    JointPlant b(p);
    ASSERT_TRUE(b.load_state(saved));
    EXPECT_EQ(b.save_state(), saved);
    for (int k = 700; k < 1400; ++k) ASSERT_TRUE(b.advance(1e-3, drive(k)));
    EXPECT_EQ(a.save_state(), b.save_state());
    EXPECT_EQ(a.time(), b.time());
}

TEST(EffectsState, PlantRejectsMalformedState) {
    JointPlant j(everything_on());
    ASSERT_TRUE(j.initialize(0.0));
    const std::vector<double> good = j.save_state();
    EXPECT_FALSE(j.load_state(std::vector<double>(good.begin(), good.end() - 1)));
    std::vector<double> old = {1.0, 0.0, 0.0, 0.0, 0.0};  // version 1 layout
    EXPECT_FALSE(j.load_state(old));
    EXPECT_EQ(j.save_state(), good);
}

TEST(EffectsState, EstimatorRestoresExactly) {
    const Parameters p = everything_on();
    JointPlant plant(p);
    ASSERT_TRUE(plant.initialize(0.0));
    std::vector<EstimatorInputs> inputs;
    for (int k = 0; k < 1000; ++k) {
        ASSERT_TRUE(plant.advance(1e-3, drive(k)));
        const PlantOutputs o = plant.outputs();
        inputs.push_back({drive(k).i_m, o.theta_m, o.theta_l});
    }
    for (int split : {1, 2, 3, 500}) {  // inside and after the delay line's warm-up
        TorqueEstimator a(p);
        for (int k = 0; k < split; ++k) ASSERT_TRUE(recoverable(a.step(inputs[k])));
        const std::vector<double> saved = a.save_state();
        // estimator (version, UKF 6, 2 previous values, 10 outputs, 2 NIS means, samples held), the gate
        // (has a reading, its 3 values, samples since, readings gated, singular and gated runs), compliance
        // model with a 3-sample delay line, joint-state filter, samples and the sample clock (2)
        EXPECT_EQ(saved.size(), 22u + 8u + 4u + 2u * 3u + JointStateFilter::kSavedSize + 3u);
        for (int k = split; k < 1000; ++k) ASSERT_TRUE(recoverable(a.step(inputs[k])));
        TorqueEstimator b(p);
        ASSERT_TRUE(b.load_state(saved));
        EXPECT_EQ(b.save_state(), saved);
        for (int k = split; k < 1000; ++k) ASSERT_TRUE(recoverable(b.step(inputs[k])));
        EXPECT_EQ(a.save_state(), b.save_state()) << split;
        EXPECT_NE(a.outputs().hysteresis_torque, 0.0);
        EXPECT_TRUE(std::isfinite(a.outputs().tau_hat));
    }
}

TEST(EffectsState, EstimatorRejectsStateOfAnotherDelay) {
    Parameters p = everything_on();
    TorqueEstimator a(p);
    a.step({0.1, 0.0, 0.0});
    const std::vector<double> saved = a.save_state();
    p.i_delay = 5e-3;  // a longer line: the saved state is too short for it
    TorqueEstimator b(p);
    const std::vector<double> before = b.save_state();
    EXPECT_FALSE(b.load_state(saved));
    EXPECT_EQ(b.save_state(), before);
}

}  // namespace
}  // namespace hdjoint
