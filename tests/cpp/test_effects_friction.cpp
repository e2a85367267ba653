// Beyond the paper: Stribeck friction (Fs, omega_s), friction drift
// (Fc_drift), the plant's friction warm-up (thermal_gain, thermal_tc),
// cogging (cog_order, cog_a, cog_b) and link friction (Fl).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

#include "friction.h"
#include "joint_plant.h"
#include "paper_equivalence.h"
#include "parameters.h"
#include "torque_estimator.h"

namespace hdjoint {
namespace {

constexpr double kPi = 3.141592653589793;

// A plant with exact encoders, started at rest at zero load and then set
// spinning: omega_m = w, omega_l = w/N, no torsion.
JointPlant spinning(const Parameters& p, double w) {
    JointPlant j(p);
    EXPECT_TRUE(j.initialize(0.0));
    std::vector<double> s = j.save_state();
    s[2] = w;
    s[4] = w / p.N;
    EXPECT_TRUE(j.load_state(s));
    return j;
}

// d omega_m/dt of a plant state (from the model's right-hand side).
double motor_acceleration(const JointPlant& j, double i_m) {
    PlantFullState dx;
    EXPECT_TRUE(j.derivative(j.full_state(), j.time(), {i_m, 0.0}, &dx, nullptr));
    return dx(1);
}

// ---- Stribeck ------------------------------------------------------------------

TEST(EffectsFriction, StribeckRaisesFrictionAtLowSpeedByFs) {
    Parameters p;
    p.Fs = 0.02;
    p.omega_s = 20.0;
    const Parameters paper;
    // Well above omega_fc (tanh = 1) and well below omega_s: larger by ~Fs.
    const double low = 5.0 * p.omega_fc;
    EXPECT_NEAR(coulomb_friction(low, p) - coulomb_friction(low, paper), p.Fs, 0.07 * p.Fs);
    EXPECT_NEAR(coulomb_friction(-low, p) - coulomb_friction(-low, paper), -p.Fs, 0.07 * p.Fs);
    // Far above omega_s the Stribeck term is gone.
    EXPECT_NEAR(coulomb_friction(10.0 * p.omega_s, p), coulomb_friction(10.0 * p.omega_s, paper), 1e-12);
    // The exact law.
    for (double w : {-50.0, -3.0, 0.2, 7.0, 40.0})
        EXPECT_NEAR(coulomb_friction(w, p),
                    (p.Fc + p.Fs * std::exp(-(w / p.omega_s) * (w / p.omega_s))) * std::tanh(w / p.omega_fc), 1e-16);
    // In the plant the motor decelerates harder by Fs/Jm at low speed.
    const double w = 5.0;
    const double extra = motor_acceleration(spinning(paper, w), 0.0) - motor_acceleration(spinning(p, w), 0.0);
    EXPECT_NEAR(extra * p.Jm, p.Fs * std::exp(-(w / p.omega_s) * (w / p.omega_s)) * std::tanh(w / p.omega_fc), 1e-12);
}

TEST(EffectsFriction, FrictionSlopesMatchDifferences) {
    Parameters p;
    p.Fs = 0.03;
    p.omega_s = 4.0;
    p.Fl = 1.5;
    p.cog_a = 0.01;
    p.cog_b = -0.004;
    const double h = 1e-6;
    for (double w : {-9.0, -0.7, 0.05, 1.3, 12.0}) {
        for (double scale : {1.0, 1.7}) {
            EXPECT_NEAR(coulomb_friction_slope(w, p, scale),
                        (coulomb_friction(w + h, p, scale) - coulomb_friction(w - h, p, scale)) / (2 * h), 1e-7);
        }
        EXPECT_NEAR(link_friction_slope(w / p.N, p),
                    (link_friction(w / p.N + h, p) - link_friction(w / p.N - h, p)) / (2 * h), 1e-4);
        EXPECT_NEAR(cogging_slope(w, p), (cogging_torque(w + h, p) - cogging_torque(w - h, p)) / (2 * h), 1e-8);
    }
}

// ---- drift and warm-up -------------------------------------------------------------

TEST(EffectsFriction, DriftAndWarmUpScales) {
    Parameters p;
    EXPECT_EQ(friction_drift_scale(123.0, p), 1.0);
    EXPECT_EQ(plant_friction_scale(123.0, p), 1.0);
    p.Fc_drift = 0.004;
    EXPECT_DOUBLE_EQ(friction_drift_scale(50.0, p), 1.2);
    p.Fc_drift = -0.01;
    EXPECT_EQ(friction_drift_scale(200.0, p), 0.0);  // held at zero: friction never drives
    p.Fc_drift = 0.0;
    p.thermal_gain = 0.6;
    p.thermal_tc = 2.0;
    EXPECT_EQ(plant_friction_scale(0.0, p), 1.0);
    EXPECT_NEAR(plant_friction_scale(2.0, p), 1.0 + 0.6 * (1.0 - std::exp(-1.0)), 1e-15);
    EXPECT_NEAR(plant_friction_scale(100.0, p), 1.6, 1e-15);  // t >> tc: 1 + gain
    p.Fc_drift = 0.001;
    EXPECT_NEAR(plant_friction_scale(100.0, p), 1.1 * 1.6, 1e-14);  // both: the product
}

TEST(EffectsFriction, PlantWarmUpReachesOnePlusGain) {
    Parameters p;
    p.thermal_gain = 0.8;
    p.thermal_tc = 0.02;
    p.Fs = 0.01;
    JointPlant j = spinning(p, 30.0);
    const double before = j.internals().tau_friction;
    for (int k = 0; k < 300; ++k) ASSERT_TRUE(j.advance(1e-3, {0.6, 0.0}));  // 15 tc
    EXPECT_NEAR(j.time(), 0.3, 1e-12);
    const PlantInternals r = j.internals();
    const double scale = 1.0 + 0.8 * (1.0 - std::exp(-0.3 / 0.02));
    EXPECT_NEAR(r.friction_scale, scale, 1e-15);
    EXPECT_NEAR(r.friction_scale, 1.8, 1e-6);
    EXPECT_NEAR(r.tau_friction, scale * coulomb_friction(j.state()(1), p) + p.Bm * j.state()(1), 1e-12);
    EXPECT_GT(r.tau_friction, before);
}

TEST(EffectsFriction, EstimatorDriftScalesTheUkfInput) {
    Parameters p;
    p.Fc_drift = 0.01;
    p.Fs = 0.005;
    TorqueEstimator e(p);
    for (int k = 0; k < 400; ++k) {
        const double theta_m = 0.02 * k * k * 1e-3;  // accelerating motor
        const EstimatorInputs in{0.3, theta_m, theta_m / p.N};
        ASSERT_EQ(e.step(in), EstimatorStatus::Ok);
        const double u = e.ukf_input();  // eq. (11)'s input of this sample
        const double scale = 1.0 + p.Fc_drift * k * p.Ts;
        EXPECT_NEAR(u, p.Kt * in.i_m - scale * coulomb_friction(e.outputs().omega_m, p), 1e-15) << k;
    }
}

// ---- cogging -------------------------------------------------------------------------

// A motor turned at pi rad/s by a stiff PI speed loop: with cogging the
// current ripples at cog_order periods per motor revolution (3 Hz for order
// 6), by about cog amplitude / Kt; without, there is no ripple there. The
// 2 s window holds whole periods of every ripple (the eq. (7) terms at 1 and
// 2 Hz, cogging at 3 Hz), so the DFT does not leak between them.
double current_ripple(const Parameters& p, double frequency, double* mean_current) {
    JointPlant j(p);
    EXPECT_TRUE(j.initialize(0.0));
    const double w_ref = kPi, kp = 0.2, ki = 8.0, dt = 1e-4;
    double integral = 0.0;
    std::vector<double> current;
    for (int k = 0; k < 40000; ++k) {
        const double error = w_ref - j.state()(1);
        integral += error * dt;
        const double i = kp * error + ki * integral;
        EXPECT_TRUE(j.advance(dt, {i, 0.0}));
        if (k >= 20000) current.push_back(i);
    }
    double mean = 0.0;
    for (double i : current) mean += i;
    mean /= static_cast<double>(current.size());
    std::complex<double> c = 0.0;
    for (std::size_t k = 0; k < current.size(); ++k)
        c += (current[k] - mean) * std::exp(std::complex<double>(0.0, -2.0 * kPi * frequency * k * dt));
    *mean_current = mean;
    return 2.0 * std::abs(c) / static_cast<double>(current.size());
}

TEST(EffectsFriction, CoggingGivesACurrentRippleAtItsOrder) {
    Parameters p;
    p.motor_counts = 0.0;
    p.link_counts = 0.0;
    p.mgl = 0.0;
    p.cog_order = 6.0;
    p.cog_a = 0.004;
    p.cog_b = 0.003;  // amplitude 0.005 N.m
    const double f = p.cog_order * kPi / (2.0 * kPi);  // 6 periods per revolution at pi rad/s: 3 Hz
    double mean = 0.0, mean_paper = 0.0;
    const double ripple = current_ripple(p, f, &mean);
    const double off_order = current_ripple(p, 0.5 * f, &mean);
    const Parameters paper_like = [&] { Parameters q = p; q.cog_a = q.cog_b = 0.0; return q; }();
    const double none = current_ripple(paper_like, f, &mean_paper);
    const double expected = 0.005 / p.Kt;
    EXPECT_NEAR(ripple, expected, 0.1 * expected);
    EXPECT_LT(none, 0.01 * expected);
    EXPECT_LT(off_order, 0.05 * expected);
    EXPECT_NEAR(mean, mean_paper, 0.02 * std::fabs(mean_paper));  // cogging averages out
}

TEST(EffectsFriction, EstimatorInputCarriesCogging) {
    Parameters p;
    p.cog_order = 4.0;
    p.cog_a = 0.01;
    p.cog_b = 0.02;
    TorqueEstimator e(p);
    for (int k = 0; k < 50; ++k) {
        const EstimatorInputs in{0.1, 0.05 * k, 0.05 * k / p.N};
        ASSERT_EQ(e.step(in), EstimatorStatus::Ok);
        const double cog = p.cog_a * std::cos(4.0 * in.theta_m) + p.cog_b * std::sin(4.0 * in.theta_m);
        EXPECT_NEAR(e.ukf_input(), p.Kt * in.i_m + cog - coulomb_friction(e.outputs().omega_m, p), 1e-15);
    }
}

// ---- link friction ------------------------------------------------------------------

// Link friction holds the link against an external torque inside +-Fl (it
// creeps at most at omega_fl, the smoothing) and lets it go outside.
TEST(EffectsFriction, LinkFrictionHoldsInsideItsBand) {
    Parameters p;
    p.motor_counts = p.link_counts = 0.0;
    p.mgl = 0.0;
    p.Fc = 0.0;  // no motor friction to hold the link instead
    p.Bm = 0.0;
    p.Bl = 0.0;
    p.Fl = 2.0;
    auto travel = [&](double tau_ext) {
        JointPlant j(p);
        EXPECT_TRUE(j.initialize(0.0));
        const double start = j.state()(2);
        for (int k = 0; k < 500; ++k) EXPECT_TRUE(j.advance(1e-3, {0.0, tau_ext}));
        return j.state()(2) - start;
    };
    const double creep = p.omega_fl * std::atanh(0.5) * 0.5;  // at tau_ext = Fl/2 for 0.5 s
    EXPECT_LT(std::fabs(travel(0.5 * p.Fl)), 1.05 * creep);
    EXPECT_LT(std::fabs(travel(-0.5 * p.Fl)), 1.05 * creep);
    EXPECT_LT(travel(2.0 * p.Fl), -0.5);  // (2Fl - Fl)/Jl * 0.5^2/2 = 1.7 rad
    Parameters free = p;
    free.Fl = 0.0;
    p = free;
    // Without it the same torque turns the link (and the motor behind it:
    // inertia Jl + N^2*Jm): 1/0.359 * 0.5^2/2 = 0.35 rad.
    EXPECT_LT(travel(0.5 * 2.0), -0.3);
}

// ---- off means off -------------------------------------------------------------------

// The switch of each effect off, with its other parameters changed: the
// model is bit for bit the paper's.
TEST(EffectsFriction, SwitchedOffIsBitIdentical) {
    Parameters p;
    p.omega_s = 3.0;      // Fs = 0
    p.cog_order = 17.0;   // cog_a = cog_b = 0
    p.thermal_tc = 0.5;   // thermal_gain = 0
    ASSERT_NO_FATAL_FAILURE(expect_paper_model_bit_for_bit(p, 1.5, 5e-3, 0.2));
}

}  // namespace
}  // namespace hdjoint
