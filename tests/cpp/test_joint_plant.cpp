// The joint (joint_plant.h): static equilibrium, conservation laws, the
// torsional resonance, ROS2's order and stiff stability, encoders, state
// save/restore, sign conventions.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "joint_plant.h"
#include "parameters.h"
#include "transmission.h"

namespace hdjoint {
namespace {

constexpr double kPi = 3.141592653589793;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// No dissipation, no gravity, no kinematic error, exact encoders.
Parameters conservative(double Cf, double Cw) {
    Parameters p;
    p.Fc = p.Bm = p.Bl = p.Df = 0.0;
    p.mgl = 0.0;
    p.al1 = p.bl1 = p.aw1 = p.bw1 = p.aw2 = p.bw2 = 0.0;
    p.Cf = Cf;
    p.Cw = Cw;
    p.motor_counts = p.link_counts = 0.0;
    return p;
}

double chain_torsion(double tau, const Parameters& p) {
    return flexspline_torsion(tau, p) + wave_generator_torsion(tau / p.N, p);
}

// Elastic energy stored at an elastic torsion y: integral of tau dy =
// T*y - integral_0^T y(t) dt (Simpson on the torque).
double elastic_energy(double y, const Parameters& p) {
    double T = 0.0;
    if (!transmitted_torque(y, p, &T)) return kNaN;
    const int n = 2000;
    const double h = T / n;
    double s = 0.0;
    for (int i = 0; i <= n; ++i) s += (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0)) * chain_torsion(i * h, p);
    return T * y - s * h / 3.0;
}

double kinetic_energy(const JointPlant& j) {
    const PlantState& x = j.state();
    const Parameters& p = j.parameters();
    return 0.5 * p.Jm * x(1) * x(1) + 0.5 * p.Jl * x(3) * x(3);
}

double total_energy(const JointPlant& j) {
    const PlantState& x = j.state();
    const Parameters& p = j.parameters();
    return kinetic_energy(j) + elastic_energy(total_torsion(x(0), x(2), p) - kinematic_error(x(0), x(2), p), p);
}

// A plant at rest at zero torque, then its motor turned by `dtheta_m`
// (zero momentum, torsion dtheta_m/N).
JointPlant displaced(const Parameters& p, double dtheta_m) {
    JointPlant j(p);
    EXPECT_TRUE(j.initialize(0.0));
    std::vector<double> s = j.save_state();
    s[1] += dtheta_m;  // [version, theta_m, omega_m, theta_l, omega_l]
    EXPECT_TRUE(j.load_state(s));
    return j;
}

// ---- static equilibrium ----------------------------------------------------

TEST(JointPlant, InitializeIsStaticEquilibrium) {
    Parameters p;  // defaults: friction, gravity, kinematic error all on
    p.theta_l0 = 0.5;
    p.Df = 2.0;
    const double tau_ext = 1.0;
    const double tau = p.mgl * std::sin(p.theta_l0) + tau_ext;
    JointPlant j(p);
    std::string msg;
    ASSERT_TRUE(j.initialize(tau_ext, &msg)) << msg;
    const PlantState x0 = j.state();
    EXPECT_EQ(x0(1), 0.0);
    EXPECT_EQ(x0(3), 0.0);
    EXPECT_EQ(x0(2), p.theta_l0);
    // The angles satisfy the compliance chain with the holding torque.
    EXPECT_NEAR(total_torsion(x0(0), x0(2), p) - kinematic_error(x0(0), x0(2), p), chain_torsion(tau, p), 1e-15);
    EXPECT_NEAR(j.outputs().tau_joint, tau, 1e-9);

    // Held with i = (tau/N)/Kt (Coulomb friction is tanh(0) = 0 at rest), it does not move.
    PlantInputs hold;
    hold.i_m = tau / p.N / p.Kt;
    hold.tau_ext = tau_ext;
    for (int k = 0; k < 100; ++k) ASSERT_TRUE(j.advance(5e-3, hold, &msg)) << msg;
    const PlantState x1 = j.state();
    EXPECT_NEAR(x1(0), x0(0), 1e-9);
    EXPECT_NEAR(x1(2), x0(2), 1e-11);
    EXPECT_NEAR(x1(1), 0.0, 1e-8);
    EXPECT_NEAR(x1(3), 0.0, 1e-10);
    EXPECT_NEAR(j.outputs().tau_joint, tau, 1e-7);

    // Control: 10% less current and it does move.
    JointPlant k(p);
    ASSERT_TRUE(k.initialize(tau_ext));
    PlantInputs weak = hold;
    weak.i_m *= 0.9;
    ASSERT_TRUE(k.advance(0.5, weak));
    EXPECT_GT(std::fabs(k.state()(2) - x0(2)), 1e-4);
}

TEST(JointPlant, InitializeWithoutKinematicErrorIsTheIdealGearPlusSpring) {
    Parameters p = conservative(0.0645, 10.0);
    p.theta_l0 = -0.3;
    p.mgl = 5.0;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    const double tau = p.mgl * std::sin(-0.3);
    EXPECT_NEAR(j.state()(0), p.N * (-0.3 + chain_torsion(tau, p)), 1e-12);
    EXPECT_NEAR(j.outputs().tau_joint, tau, 1e-9);
}

TEST(JointPlant, InitializeWithALargeKinematicError) {
    // 7 arcmin amplitudes (5x a catalogue drive's): N*d(theta_err)/d(theta_m)
    // reaches ~0.6, the fixed point must still be found exactly.
    Parameters p;
    p.aw1 = 2e-3;
    p.bw1 = 2e-3;
    p.theta_l0 = 0.3;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    const double tau = p.mgl * std::sin(0.3);
    const PlantState& x = j.state();
    EXPECT_NEAR(total_torsion(x(0), x(2), p) - kinematic_error(x(0), x(2), p), chain_torsion(tau, p), 1e-14);
    EXPECT_NEAR(j.outputs().tau_joint, tau, 1e-9);
}

TEST(JointPlant, InitializeFailsWhenNoTorqueHoldsTheLoad) {
    Parameters p;
    JointPlant j(p);
    std::string msg;
    EXPECT_FALSE(j.initialize(1e14, &msg));  // beyond what the atan law can carry
    EXPECT_FALSE(msg.empty());
}

// ---- sign conventions (CONTRACT.md) ------------------------------------------

TEST(JointPlant, SignConventions) {
    Parameters p;
    p.mgl = 0.0;
    p.motor_counts = p.link_counts = 0.0;
    {
        // Positive current turns motor and link positive through a positive joint torque.
        JointPlant j(p);
        ASSERT_TRUE(j.initialize(0.0));
        const PlantState x0 = j.state();
        PlantInputs in;
        in.i_m = 1.0;
        ASSERT_TRUE(j.advance(0.05, in));
        EXPECT_GT(j.state()(0), x0(0));
        EXPECT_GT(j.state()(2), x0(2));
        EXPECT_GT(j.outputs().tau_joint, 0.0);
        EXPECT_GT(j.outputs().omega_m, 0.0);
        EXPECT_GT(j.outputs().omega_link, 0.0);
    }
    {
        // Positive tau_ext acts like gravity's mgl*sin(theta_l): it pushes the
        // link negative, and the drive resists with a positive joint torque.
        JointPlant j(p);
        ASSERT_TRUE(j.initialize(0.0));
        PlantInputs in;
        in.tau_ext = 2.0;
        ASSERT_TRUE(j.advance(0.05, in));
        EXPECT_LT(j.state()(2), p.theta_l0);
        EXPECT_LT(j.state()(3), 0.0);
        EXPECT_GT(j.outputs().tau_joint, 0.0);
    }
    {
        // Gravity: a link held at positive angle needs positive joint torque.
        Parameters g = p;
        g.mgl = 5.0;
        g.theta_l0 = 0.4;
        JointPlant j(g);
        ASSERT_TRUE(j.initialize(0.0));
        EXPECT_NEAR(j.outputs().tau_joint, 5.0 * std::sin(0.4), 1e-9);
        EXPECT_GT(j.state()(0) / g.N, g.theta_l0);  // the motor leads the link
    }
}

// ---- conservation laws --------------------------------------------------------

TEST(JointPlant, FreeOscillationConservesEnergyLinearChain) {
    Parameters p = conservative(0.0, 0.0);
    p.max_step = 1e-5;
    JointPlant j = displaced(p, 0.1);  // torsion 1e-3 rad
    const double E0 = total_energy(j);
    const double K = 1.0 / (1.0 / p.Kf + 1.0 / (p.N * p.N * p.Kw));
    EXPECT_NEAR(E0, 0.5 * K * 1e-3 * 1e-3, 1e-9 * E0);  // the energy formula itself
    double max_kinetic = 0.0, worst = 0.0;
    for (int k = 0; k < 1000; ++k) {
        ASSERT_TRUE(j.advance(1e-3, PlantInputs{}));
        worst = std::max(worst, std::fabs(total_energy(j) - E0));
        max_kinetic = std::max(max_kinetic, kinetic_energy(j));
    }
    EXPECT_LT(worst, 2e-4 * E0);
    EXPECT_GT(max_kinetic, 0.9 * E0);  // energy really went back and forth
}

TEST(JointPlant, FreeOscillationConservesEnergyNonlinearChain) {
    // The default (stiffening) flexspline and (saturating) wave generator.
    Parameters p = conservative(0.0645, 10.0);
    p.max_step = 1e-5;
    JointPlant j = displaced(p, 0.1);
    const double E0 = total_energy(j);
    // Nonlinear enough that a quadratic energy would be wrong by far more than the tolerance.
    const double K0 = 1.0 / (1.0 / p.Kf + 1.0 / (p.N * p.N * p.Kw));
    EXPECT_GT(std::fabs(E0 - 0.5 * K0 * 1e-6) / E0, 0.05);
    double max_kinetic = 0.0, worst = 0.0, max_tau = 0.0;
    for (int k = 0; k < 1000; ++k) {
        ASSERT_TRUE(j.advance(1e-3, PlantInputs{}));
        worst = std::max(worst, std::fabs(total_energy(j) - E0));
        max_kinetic = std::max(max_kinetic, kinetic_energy(j));
        max_tau = std::max(max_tau, std::fabs(j.outputs().tau_joint));
    }
    EXPECT_LT(worst, 5e-4 * E0);
    EXPECT_GT(max_kinetic, 0.9 * E0);
    EXPECT_GT(max_tau * p.Cf, 0.3);  // well into the nonlinear range
}

TEST(JointPlant, InternalTorquesConserveAngularMomentum) {
    // With no external torque, N*Jm*omega_m + Jl*omega_l is constant, even
    // with structural damping and kinematic error (internal to the drive):
    // ROS2 keeps linear invariants exactly when the Jacobian respects them.
    Parameters p = conservative(0.0645, 10.0);
    p.Df = 3.0;
    p.al1 = 1e-4;
    p.aw1 = 0.6e-4;
    p.bw2 = 0.1e-4;
    JointPlant j = displaced(p, 0.05);
    std::vector<double> s = j.save_state();
    s[2] = 30.0;  // spinning motor
    s[4] = 0.1;
    ASSERT_TRUE(j.load_state(s));
    auto momentum = [&] { return p.N * p.Jm * j.state()(1) + p.Jl * j.state()(3); };
    const double L0 = momentum();
    for (int k = 0; k < 500; ++k) {
        ASSERT_TRUE(j.advance(1e-3, PlantInputs{}));
        ASSERT_NEAR(momentum(), L0, 1e-12 * std::fabs(L0)) << k;
    }
    // Damping took the free oscillation out (what is left is forced by the
    // kinematic error): motor and link turn together, where they started 0.2 rad/s apart.
    EXPECT_LT(std::fabs(j.state()(1) / p.N - j.state()(3)), 0.02);
}

// ---- the torsional resonance -----------------------------------------------------

TEST(JointPlant, TorsionalResonanceFrequency) {
    for (double Cf : {0.0645, 0.0}) {
        Parameters p = conservative(Cf, Cf > 0.0 ? 10.0 : 0.0);  // default max_step = 1e-4
        JointPlant j = displaced(p, 1e-6);                         // small amplitude: the linearisation at 0
        const double K = 1.0 / (1.0 / p.Kf + 1.0 / (p.N * p.N * p.Kw));
        const double omega = std::sqrt(K * (1.0 / (p.Jm * p.N * p.N) + 1.0 / p.Jl));
        const double dt = p.max_step;
        double previous = j.outputs().tau_joint;
        std::vector<double> up;  // upward zero crossings of the joint torque
        const int n = static_cast<int>(std::lround(0.5 / dt));
        for (int k = 0; k < n; ++k) {
            ASSERT_TRUE(j.advance(dt, PlantInputs{}));
            const double c = j.outputs().tau_joint;
            if (previous < 0.0 && c >= 0.0) up.push_back((k + 1) * dt - dt * c / (c - previous));
            previous = c;
        }
        ASSERT_GT(up.size(), 10u);
        const double period = (up.back() - up.front()) / static_cast<double>(up.size() - 1);
        EXPECT_NEAR(2.0 * kPi / period, omega, 0.01 * omega) << "Cf = " << Cf;
    }
}

// ---- the integrator -----------------------------------------------------------------

PlantState run_reference_trajectory(double max_step) {
    Parameters p;  // all the default nonlinearities and friction
    p.max_step = max_step;
    JointPlant j(p);
    EXPECT_TRUE(j.initialize(0.5));
    for (int k = 0; k < 50; ++k) {
        PlantInputs in;
        in.i_m = 1.5 * std::sin(2.0 * kPi * 20.0 * k * 1e-3) + 0.3;
        in.tau_ext = 0.5;
        EXPECT_TRUE(j.advance(1e-3, in));
    }
    return j.state();
}

double scaled_error(const PlantState& x, const PlantState& ref, double N) {
    Vector<4> scale;
    scale << 1.0 / N, 1.0 / N, 1.0, 1.0;  // motor-side quantities seen at the link
    return (x - ref).cwiseProduct(scale).norm();
}

TEST(JointPlant, Ros2IsSecondOrder) {
    const Parameters p;
    const PlantState ref = run_reference_trajectory(1e-6);
    const double e1 = scaled_error(run_reference_trajectory(1e-4), ref, p.N);
    const double e2 = scaled_error(run_reference_trajectory(5e-5), ref, p.N);
    const double e3 = scaled_error(run_reference_trajectory(2.5e-5), ref, p.N);
    EXPECT_GT(e1, 1e-6);  // measurably inexact, far above the reference's own error
    EXPECT_GT(e1 / e2, 3.5) << e1 << " " << e2;
    EXPECT_LT(e1 / e2, 4.8) << e1 << " " << e2;
    EXPECT_GT(e2 / e3, 3.5) << e2 << " " << e3;
    EXPECT_LT(e2 / e3, 4.8) << e2 << " " << e3;
}

TEST(JointPlant, AdvanceSplitsIntoEqualSubstepsOfAtMostMaxStep) {
    Parameters p;
    p.max_step = 1e-4;
    PlantInputs in;
    in.i_m = 0.7;
    JointPlant a(p), b(p);
    ASSERT_TRUE(a.initialize(0.2));
    ASSERT_TRUE(b.initialize(0.2));
    ASSERT_TRUE(a.advance(2.5e-4, in));                       // 3 substeps of 8.33e-5
    for (int k = 0; k < 3; ++k) ASSERT_TRUE(b.advance(2.5e-4 / 3.0, in));
    EXPECT_LT((a.state() - b.state()).cwiseAbs().maxCoeff(), 1e-13);
    // A zero or negative step changes nothing.
    const PlantState x = a.state();
    EXPECT_TRUE(a.advance(0.0, in));
    EXPECT_TRUE(a.advance(-1.0, in));
    EXPECT_EQ(a.state(), x);
}

TEST(JointPlant, StableWithStiffFrictionSmoothing) {
    // omega_fc = 1e-4: the friction slope Fc/omega_fc over Jm is ~7e6 1/s,
    // ~700 times the inverse substep. An explicit method would blow up.
    auto run = [](double max_step, double* max_omega, double* max_tau) {
        Parameters p;
        p.omega_fc = 1e-4;
        p.max_step = max_step;
        JointPlant j(p);
        EXPECT_TRUE(j.initialize(0.0));
        *max_omega = *max_tau = 0.0;
        for (int k = 0; k < 100; ++k) {
            const double t = k * 0.01;
            PlantInputs in;
            in.i_m = 0.8 * std::sin(2.0 * kPi * 2.0 * t);
            in.tau_ext = 0.3 * std::sin(2.0 * kPi * 0.5 * t);
            std::string msg;
            EXPECT_TRUE(j.advance(0.01, in, &msg)) << msg;
            const PlantOutputs o = j.outputs();
            EXPECT_TRUE(std::isfinite(o.omega_m) && std::isfinite(o.tau_joint) && std::isfinite(o.theta_m));
            *max_omega = std::max(*max_omega, std::fabs(o.omega_m));
            *max_tau = std::max(*max_tau, std::fabs(o.tau_joint));
        }
        return j.state();
    };
    double w1 = 0.0, t1 = 0.0, w2 = 0.0, t2 = 0.0;
    const PlantState coarse = run(1e-4, &w1, &t1);
    const PlantState fine = run(1e-5, &w2, &t2);
    ASSERT_TRUE(coarse.allFinite());
    // Bounded: no-load speed Kt*i/Bm would be 1200 rad/s; the real motion is ~90 rad/s.
    EXPECT_LT(w1, 150.0);
    EXPECT_LT(t1, 10.0);
    // ... and still accurate against a 10x finer run.
    EXPECT_NEAR(coarse(1), fine(1), 0.03 * std::fabs(fine(1)));
    EXPECT_NEAR(coarse(0), fine(0), 0.03 * std::fabs(fine(0)));
    EXPECT_NEAR(w1, w2, 0.03 * w2);
}

TEST(JointPlant, StiffCoulombFrictionHoldsTheMotorBelowBreakaway) {
    Parameters p;
    p.omega_fc = 1e-4;
    p.mgl = 0.0;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    const PlantState x0 = j.state();
    PlantInputs in;
    in.i_m = 0.6 * p.Fc / p.Kt;  // 60% of the Coulomb torque
    for (int k = 0; k < 50; ++k) ASSERT_TRUE(j.advance(0.01, in));
    EXPECT_LT(std::fabs(j.state()(1)), 1e-3);        // creeps at most at ~omega_fc
    EXPECT_LT(std::fabs(j.state()(0) - x0(0)), 1e-3);
    // Above breakaway it turns.
    in.i_m = 2.0 * p.Fc / p.Kt;
    ASSERT_TRUE(j.advance(0.05, in));
    EXPECT_GT(j.state()(1), 1.0);
}

// ---- encoders -------------------------------------------------------------------------

TEST(Quantise, WholeCountsFloorAndIdentity) {
    const double counts = 4096.0;
    const double res = 2.0 * kPi / counts;
    for (double angle : {0.0, 1e-9, 0.3, 1.0, 6.0, 123.456, -1e-9, -0.3, -123.456}) {
        const double q = quantise(angle, counts);
        const double n = q / res;
        EXPECT_NEAR(n, std::round(n), 1e-6 * (1.0 + std::fabs(n))) << angle;  // whole counts
        EXPECT_LE(q, angle + 1e-12) << angle;                                  // floor ...
        EXPECT_GT(q, angle - res) << angle;                                    // ... by less than a count
    }
    // Floor, not round: mid-count and just-below-a-count readings go down.
    EXPECT_NEAR(quantise(10.5 * res, counts), 10.0 * res, 1e-15);
    EXPECT_NEAR(quantise(10.999 * res, counts), 10.0 * res, 1e-15);
    EXPECT_NEAR(quantise(-0.5 * res, counts), -res, 1e-15);  // towards -infinity
    EXPECT_NEAR(quantise(-10.5 * res, counts), -11.0 * res, 1e-15);
    EXPECT_EQ(quantise(0.0, counts), 0.0);
    // The 19-bit link encoder.
    const double lres = 2.0 * kPi / 524288.0;
    EXPECT_NEAR(quantise(1000.7 * lres, 524288.0), 1000.0 * lres, 1e-15);
    // 0 counts: no quantisation.
    for (double angle : {0.123456789, -7.7, 0.0}) EXPECT_EQ(quantise(angle, 0.0), angle);
}

TEST(JointPlant, OutputsAreQuantisedEncoderReadings) {
    Parameters p;
    p.theta_l0 = 0.3;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    const PlantOutputs o = j.outputs();
    EXPECT_EQ(o.theta_m, quantise(j.state()(0), p.motor_counts));
    EXPECT_EQ(o.theta_l, quantise(j.state()(2), p.link_counts));
    EXPECT_NE(o.theta_m, j.state()(0));
    p.motor_counts = p.link_counts = 0.0;
    JointPlant exact(p);
    ASSERT_TRUE(exact.initialize(0.0));
    EXPECT_EQ(exact.outputs().theta_m, exact.state()(0));
    EXPECT_EQ(exact.outputs().theta_l, exact.state()(2));
}

// ---- state save/restore ---------------------------------------------------------------

TEST(JointPlant, SaveLoadStateContinuesExactly) {
    Parameters p;
    p.Df = 1.0;
    auto input = [](int k) {
        PlantInputs in;
        in.i_m = 1.2 * std::sin(0.031 * k) + 0.2 * std::sin(0.7 * k);
        in.tau_ext = 0.4 * std::cos(0.011 * k);
        return in;
    };
    JointPlant a(p);
    ASSERT_TRUE(a.initialize(0.4));
    for (int k = 0; k < 100; ++k) ASSERT_TRUE(a.advance(1e-3, input(k)));
    const std::vector<double> saved = a.save_state();

    JointPlant b(p);
    ASSERT_TRUE(b.initialize(-1.0));  // a different history, overwritten by the load
    ASSERT_TRUE(b.load_state(saved));
    EXPECT_EQ(b.state(), a.state());
    for (int k = 100; k < 200; ++k) {
        ASSERT_TRUE(a.advance(1e-3, input(k)));
        ASSERT_TRUE(b.advance(1e-3, input(k)));
        const PlantOutputs oa = a.outputs(), ob = b.outputs();
        ASSERT_EQ(oa.theta_m, ob.theta_m) << k;
        ASSERT_EQ(oa.theta_l, ob.theta_l) << k;
        ASSERT_EQ(oa.tau_joint, ob.tau_joint) << k;
        ASSERT_EQ(oa.omega_m, ob.omega_m) << k;
        ASSERT_EQ(oa.omega_link, ob.omega_link) << k;
    }
    EXPECT_EQ(a.save_state(), b.save_state());
    EXPECT_NE(a.save_state(), saved);
}

TEST(JointPlant, LoadStateRejectsMalformedData) {
    const Parameters p;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    const std::vector<double> good = j.save_state();
    const PlantState x = j.state();
    EXPECT_FALSE(j.load_state({}));
    EXPECT_FALSE(j.load_state(std::vector<double>(good.begin(), good.end() - 1)));
    std::vector<double> longer = good;
    longer.push_back(1.0);
    EXPECT_FALSE(j.load_state(longer));
    std::vector<double> version = good;
    version[0] = 99.0;
    EXPECT_FALSE(j.load_state(version));
    EXPECT_EQ(j.state(), x);
}

// ---- leaving the model's domain ---------------------------------------------------------

// load_state() checks every value as the FMU's fmi2DeSerializeFMUstate does
// (one reading, state_fields.h): a non-finite angle, a negative time or a
// version that is not a whole number is refused, and the plant is left as it was.
TEST(JointPlant, LoadStateRefusesValuesTheFmuRefuses) {
    const Parameters p;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    const std::vector<double> good = j.save_state();
    const PlantState x = j.state();
    const std::vector<std::pair<std::size_t, double>> edits = {
        {1, kNaN}, {2, std::numeric_limits<double>::infinity()}, {5, -1.0}, {0, 3.5}};
    for (const auto& [field, value] : edits) {
        std::vector<double> s = good;
        s[field] = value;
        EXPECT_FALSE(j.load_state(s)) << "field " << field << " = " << value;
        EXPECT_EQ(j.state(), x);
    }
    EXPECT_TRUE(j.load_state(good));
}

TEST(JointPlant, AdvanceReportsASingularTorsion) {
    const Parameters p;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    std::vector<double> s = j.save_state();
    s[1] += 10.0 * p.N;  // 10 rad of torsion: beyond any torque
    ASSERT_TRUE(j.load_state(s));
    std::string msg;
    EXPECT_FALSE(j.advance(1e-3, PlantInputs{}, &msg));
    EXPECT_NE(msg.find("singular torsion"), std::string::npos) << msg;
    double tau = 0.0;
    EXPECT_FALSE(j.joint_torque(j.state(), &tau));
    EXPECT_TRUE(std::isnan(j.outputs().tau_joint));
}

// Regression (fixed in 7135e36): transmitted_torque() took a NaN torsion for
// zero torsion, so joint_torque() of a state with a NaN angle reported success
// with tau = 0 and outputs() showed tau_joint = 0 instead of NaN.
// joint_torque() is documented to return false outside the model's domain.
TEST(JointPlant, JointTorqueRejectsANonFiniteAngle) {
    const Parameters p;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    PlantState x = j.state();
    x(0) = kNaN;
    double tau = 123.0;
    EXPECT_FALSE(j.joint_torque(x, &tau)) << "tau = " << tau;
}

// Df damps the deformation: a motion along which only the kinematic error
// changes the torsion (the gears' geometry) is not damped.
TEST(JointPlant, DampingActsOnTheDeformationNotTheKinematicError) {
    Parameters p;
    p.Df = 5.0;
    p.aw1 = 2e-4;
    p.al1 = 1e-4;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    PlantState x;
    x << 1.3, 40.0, 1.3 / p.N - 1e-4, 0.0;  // a modest torsion
    double dk_dm = 0.0, dk_dl = 0.0;
    kinematic_error_gradient(x(0), x(2), p, &dk_dm, &dk_dl);
    ASSERT_GT(std::fabs(dk_dm * x(1)), 1e-4 * std::fabs(x(1) / p.N));  // the error's rate is not negligible
    x(3) = (x(1) / p.N - dk_dm * x(1)) / (1.0 + dk_dl);               // the elastic torsion stands still
    double tau = 0.0, elastic = 0.0;
    ASSERT_TRUE(j.joint_torque(x, &tau));
    ASSERT_TRUE(transmitted_torque(total_torsion(x(0), x(2), p) - kinematic_error(x(0), x(2), p), p, &elastic));
    EXPECT_NEAR(tau, elastic, 1e-12);
    x(3) += 1e-3;  // now the deformation changes: damped
    ASSERT_TRUE(j.joint_torque(x, &tau));
    EXPECT_NEAR(tau - elastic, p.Df * (-1.0 - dk_dl) * 1e-3, 1e-9);
}

// A kinematic error so steep in the motor angle that the starting angle is
// not unique is refused with a message that says so (not "singular torsion").
TEST(JointPlant, TooSteepKinematicErrorIsNamedAtStart) {
    Parameters p;
    p.aw1 = 0.02;  // N * omega_w * aw1 = 4: far beyond any real harmonic drive
    JointPlant j(p);
    std::string message;
    EXPECT_FALSE(j.initialize(0.0, &message));
    EXPECT_NE(message.find("kinematic error is too large"), std::string::npos) << message;
    EXPECT_NE(message.find("aw1"), std::string::npos) << message;
}

}  // namespace
}  // namespace hdjoint
