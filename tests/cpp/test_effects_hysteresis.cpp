// Beyond the paper: transmission hysteresis (Dahl: hys_H, hys_sigma, in the
// estimator and the plant; Bouc-Wen: bw_A, bw_beta, bw_gamma, plant only)
// and LuGre motor friction (lugre_sigma0, lugre_sigma1, plant only).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "compliance_model.h"
#include "friction.h"
#include "hysteresis.h"
#include "joint_plant.h"
#include "paper_equivalence.h"
#include "parameters.h"
#include "torque_estimator.h"
#include "transmission.h"

namespace hdjoint {
namespace {

constexpr double kPi = 3.141592653589793;

// A triangle wave between -amplitude and +amplitude, starting at 0 going up,
// `period` samples long (a multiple of 4: the turning points are samples).
double triangle(int k, int period, double amplitude) {
    const int q = period / 4;
    const int m = k % period;
    if (m <= q) return amplitude * m / q;
    if (m <= 3 * q) return amplitude * (2.0 * q - m) / q;
    return amplitude * (m - 4.0 * q) / q;
}

// ---- Dahl, the exact update ---------------------------------------------------------

TEST(EffectsHysteresis, DahlUpdateIsExactAndRateIndependent) {
    const double H = 0.4, sigma = 2e4;
    EXPECT_EQ(dahl_update(0.1, 0.0, H, sigma), 0.1);
    EXPECT_EQ(dahl_update(0.1, 1e-3, 0.0, sigma), 0.1);  // off
    // One increment or a thousand small ones in the same direction: the same z.
    double z = -0.2;
    for (int k = 0; k < 1000; ++k) z = dahl_update(z, 1e-7, H, sigma);
    EXPECT_NEAR(z, dahl_update(-0.2, 1e-4, H, sigma), 1e-14);
    // The law: dz/dx = sigma*(1 - z/H) going up, starting at slope sigma.
    EXPECT_NEAR(dahl_update(0.0, 1e-9, H, sigma) / 1e-9, sigma, 1e-4 * sigma);
    // Saturation at +-H, never beyond.
    EXPECT_NEAR(dahl_update(0.0, 1.0, H, sigma), H, 1e-15);
    EXPECT_NEAR(dahl_update(0.0, -1.0, H, sigma), -H, 1e-15);
    EXPECT_LE(dahl_update(0.39, 1e-2, H, sigma), H);
}

TEST(EffectsHysteresis, DahlLoopHasHeightTwoHAfterAFullCycle) {
    const double H = 0.4, sigma = 2e4, amplitude = 20.0 * H / sigma;
    const int period = 400;
    double z = 0.0, previous = 0.0, up = 0.0, down = 0.0;
    for (int k = 1; k <= 2 * period; ++k) {
        const double x = triangle(k, period, amplitude);
        z = dahl_update(z, x - previous, H, sigma);
        previous = x;
        if (k == period) up = z;               // second cycle, x = 0 going up... first at k = period
        if (k == period + period / 2) down = z;  // x = 0 going down
    }
    EXPECT_NEAR(up - down, 2.0 * H, 1e-6 * H);
    EXPECT_LT(up, H);
    EXPECT_GT(down, -H);
}

// ---- Dahl in the estimator ----------------------------------------------------------

// Encoder angles that put exactly `torsion` on eq. (4) at zero current (no
// kinematic error, so dtheta_f is the total torsion).
Parameters estimator_without_kinematic_error() {
    Parameters p;
    p.al1 = p.bl1 = p.aw1 = p.bw1 = p.aw2 = p.bw2 = 0.0;
    return p;
}

TEST(EffectsHysteresis, EstimatorAddsTheDahlTorqueOfTheTorsionPath) {
    Parameters p = estimator_without_kinematic_error();
    p.hys_H = 0.3;
    p.hys_sigma = 3e4;
    const Parameters paper = estimator_without_kinematic_error();
    TorqueEstimator e(p), plain(paper);
    double z = 0.0, previous = 0.0;
    for (int k = 0; k < 1200; ++k) {
        const double torsion = triangle(k, 400, 6e-4);
        const EstimatorInputs in{0.0, paper.N * (0.2 + torsion), 0.2};
        ASSERT_EQ(e.step(in), EstimatorStatus::Ok);
        ASSERT_EQ(plain.step(in), EstimatorStatus::Ok);
        if (k > 0) z = dahl_update(z, e.outputs().dtheta_f - previous, p.hys_H, p.hys_sigma);
        previous = e.outputs().dtheta_f;
        EXPECT_EQ(e.outputs().dtheta_f, plain.outputs().dtheta_f);  // eq. (4) is untouched
        EXPECT_EQ(e.outputs().hysteresis_torque, z);
        EXPECT_EQ(e.outputs().tau_compliance, plain.outputs().tau_compliance + z);
    }
}

TEST(EffectsHysteresis, EstimatorHysteresisIsRateIndependent) {
    // The same torsion path sampled 4 times more finely: at the common
    // samples the hysteresis torque is the same.
    Parameters p = estimator_without_kinematic_error();
    p.hys_H = 0.5;
    p.hys_sigma = 1e4;
    ComplianceModel coarse(p), fine(p);
    for (int k = 0; k < 4 * 1000; ++k) {
        const double torsion = triangle(k, 4 * 200, 8e-4);
        const ComplianceSample f = fine.step(0.0, p.N * (0.1 + torsion), 0.1);
        if (k % 4 == 0) {
            const ComplianceSample c = coarse.step(0.0, p.N * (0.1 + torsion), 0.1);
            ASSERT_NEAR(c.z, f.z, 1e-12) << k;
        }
    }
}

// The UKF measures the torsion that eq. (5) maps to the hysteretic torque,
// so its estimate follows tau_compliance (loop included) at rest.
TEST(EffectsHysteresis, UkfFollowsTheHystereticTorque) {
    Parameters p = estimator_without_kinematic_error();
    p.hys_H = 0.8;
    TorqueEstimator e(p);
    for (int k = 0; k < 3000; ++k) {
        const double torsion = k < 1000 ? 4e-4 * k / 1000.0 : 4e-4 - 2e-4 * std::min(1.0, (k - 1000) / 1000.0);
        ASSERT_TRUE(recoverable(e.step({0.0, p.N * (0.3 + torsion), 0.3})));
    }
    EXPECT_NEAR(e.outputs().hysteresis_torque, -0.8, 0.05);  // went down by 2e-4 >> H/sigma
    EXPECT_NEAR(e.outputs().tau_ukf, e.outputs().tau_compliance, 0.01);
}

// ---- Dahl in the plant ----------------------------------------------------------------

Parameters exact_plant() {
    Parameters p;
    p.motor_counts = p.link_counts = 0.0;
    return p;
}

// A heavy arm (gravity 50 N.m) swung a few degrees by a slow sinusoidal
// current, without kinematic error or motor Coulomb friction (whose flip at
// each reversal rings the torsional resonance): the torsion follows the load
// smoothly.
Parameters swinging_arm() {
    Parameters p = exact_plant();
    p.mgl = 50.0;
    p.Fc = 0.0;
    p.Df = 2.0;
    p.al1 = p.bl1 = p.aw1 = p.bw1 = p.aw2 = p.bw2 = 0.0;
    return p;
}

// The plant's continuous Dahl state agrees with the exact discrete update
// along its own elastic torsion, and the torque-torsion loop is 2H high.
TEST(EffectsHysteresis, PlantDahlLoop) {
    Parameters p = swinging_arm();
    p.hys_H = 0.5;
    p.hys_sigma = 2e4;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    double z = 0.0, previous = j.internals().elastic_torsion, worst = 0.0;
    std::vector<double> torsion, hysteresis;
    for (int k = 0; k < 40000; ++k) {
        const double t = k * 1e-4;
        ASSERT_TRUE(j.advance(1e-4, {2.0 * std::sin(2.0 * kPi * 0.5 * t), 0.0}));
        const PlantInternals r = j.internals();
        z = dahl_update(z, r.elastic_torsion - previous, p.hys_H, p.hys_sigma);
        previous = r.elastic_torsion;
        worst = std::max(worst, std::fabs(r.z_dahl - z));
        double tau = 0.0, elastic = 0.0;
        ASSERT_TRUE(j.joint_torque(j.state(), &tau));
        ASSERT_TRUE(transmitted_torque(r.elastic_torsion, p, &elastic));
        const double damping = p.Df * (j.state()(1) / p.N - j.state()(3));
        ASSERT_NEAR(tau - elastic - damping, r.z_dahl, 1e-12);  // the torque carries z
        if (t >= 2.0) {
            torsion.push_back(r.elastic_torsion);
            hysteresis.push_back(r.z_dahl);
        }
    }
    EXPECT_LT(worst, 0.02 * p.hys_H);
    // Over the last full cycle the hysteresis torque sweeps the loop: near
    // +H at the top of the torsion and -H at the bottom.
    const auto [lo, hi] = std::minmax_element(torsion.begin(), torsion.end());
    EXPECT_NEAR(hysteresis[hi - torsion.begin()], p.hys_H, 0.05 * p.hys_H);
    EXPECT_NEAR(hysteresis[lo - torsion.begin()], -p.hys_H, 0.05 * p.hys_H);
}

// ---- Bouc-Wen (plant) -----------------------------------------------------------------

TEST(EffectsHysteresis, PlantBoucWenLoopSaturatesAtAOverBetaPlusGamma) {
    Parameters p = swinging_arm();
    p.bw_A = 1e4;
    p.bw_beta = 1.5e4;
    p.bw_gamma = 0.5e4;  // z saturates at A/(beta + gamma) = 0.5 N.m
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    std::vector<double> torsion, z;
    for (int k = 0; k < 40000; ++k) {
        const double t = k * 1e-4;
        ASSERT_TRUE(j.advance(1e-4, {2.0 * std::sin(2.0 * kPi * 0.5 * t), 0.0}));
        const PlantInternals r = j.internals();
        ASSERT_LE(std::fabs(r.z_bouc_wen), 0.5 + 1e-9);
        if (t >= 2.0) {
            torsion.push_back(r.elastic_torsion);
            z.push_back(r.z_bouc_wen);
        }
    }
    const auto [lo, hi] = std::minmax_element(torsion.begin(), torsion.end());
    EXPECT_NEAR(z[hi - torsion.begin()], 0.5, 0.03);
    EXPECT_NEAR(z[lo - torsion.begin()], -0.5, 0.03);
    // A loop: at mid torsion the rising branch is 2*A/(beta + gamma) above the falling one.
    const double mid = 0.5 * (*lo + *hi);
    double rising = 0.0, falling = 0.0;
    for (std::size_t k = 1; k < torsion.size(); ++k) {
        if (torsion[k - 1] < mid && torsion[k] >= mid) rising = z[k];
        if (torsion[k - 1] > mid && torsion[k] <= mid) falling = z[k];
    }
    EXPECT_NEAR(rising - falling, 1.0, 0.05);
}

// ---- LuGre (plant) ----------------------------------------------------------------------

// Held at constant speed by a PI loop, the LuGre friction settles on the
// Stribeck curve g(w)*sign(w) + Bm*w.
TEST(EffectsHysteresis, LuGreSteadyStateIsTheStribeckCurve) {
    for (double w_ref : {-6.0, 2.0, 15.0}) {
        Parameters p = exact_plant();
        p.mgl = 0.0;
        p.Fs = 0.02;
        p.omega_s = 5.0;
        p.lugre_sigma0 = 1e5;
        p.lugre_sigma1 = 0.3;
        JointPlant j(p);
        ASSERT_TRUE(j.initialize(0.0));
        double integral = 0.0;
        for (int k = 0; k < 30000; ++k) {
            const double error = w_ref - j.state()(1);
            integral += error * 1e-4;
            ASSERT_TRUE(j.advance(1e-4, {0.2 * error + 8.0 * integral, 0.0}));
        }
        const double w = j.state()(1);
        ASSERT_NEAR(w, w_ref, 0.05);
        const double g = p.Fc + p.Fs * std::exp(-(w / p.omega_s) * (w / p.omega_s));
        EXPECT_NEAR(j.internals().tau_friction, std::copysign(g, w) + p.Bm * w, 2e-4 * g) << w_ref;
        EXPECT_NEAR(j.internals().z_lugre, std::copysign(g, w) / p.lugre_sigma0, 1e-3 * g / p.lugre_sigma0);
    }
}

// Below breakaway the LuGre bristles hold the motor (pre-sliding): a motor
// torque under Fc moves it only by about torque/sigma0.
TEST(EffectsHysteresis, LuGreHoldsTheMotorBelowBreakaway) {
    Parameters p = exact_plant();
    p.mgl = 0.0;
    p.lugre_sigma0 = 1e4;
    p.lugre_sigma1 = 0.05;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    const double theta_m0 = j.state()(0);
    const double drive = 0.5 * p.Fc;
    for (int k = 0; k < 5000; ++k) ASSERT_TRUE(j.advance(1e-4, {drive / p.Kt, 0.0}));
    // Bristle deflection drive/sigma0 plus a creep of about 1e-3*omega_fc for 0.5 s.
    EXPECT_LT(std::fabs(j.state()(0) - theta_m0), drive / p.lugre_sigma0 + 1e-3 * p.omega_fc * 0.5);
    EXPECT_LT(std::fabs(j.state()(1)), 1e-3 * p.omega_fc);
    // Without LuGre the smoothed Coulomb law creeps at omega_fc*atanh(0.5) rad/s.
    Parameters q = p;
    q.lugre_sigma0 = 0.0;
    JointPlant c(q);
    ASSERT_TRUE(c.initialize(0.0));
    for (int k = 0; k < 5000; ++k) ASSERT_TRUE(c.advance(1e-4, {drive / q.Kt, 0.0}));
    EXPECT_GT(std::fabs(c.state()(0) - theta_m0), 0.1);
}

// ---- off means off ---------------------------------------------------------------------

TEST(EffectsHysteresis, SwitchedOffIsBitIdentical) {
    Parameters p;
    p.hys_sigma = 7e5;     // hys_H = 0
    p.bw_beta = 3.0;       // bw_A = 0
    p.bw_gamma = 4.0;
    p.lugre_sigma1 = 0.7;  // lugre_sigma0 = 0
    ASSERT_NO_FATAL_FAILURE(expect_paper_model_bit_for_bit(p, 2.0, 7e-3, -0.4));
}

}  // namespace
}  // namespace hdjoint
