// Beyond the paper: backlash (lost motion), a dead zone of total width
// `backlash` on the flexspline torsion.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "joint_plant.h"
#include "parameters.h"
#include "torque_estimator.h"
#include "transmission.h"

namespace hdjoint {
namespace {

double chain_torsion(double tau, const Parameters& p) {
    return flexspline_torsion(tau, p) + wave_generator_torsion(tau / p.N, p);
}

TEST(EffectsBacklash, DeadZone) {
    Parameters p;
    EXPECT_EQ(backlash_deadzone(3e-4, p), 3e-4);  // off: the identity
    p.backlash = 4e-4;
    EXPECT_EQ(backlash_deadzone(0.0, p), 0.0);
    EXPECT_EQ(backlash_deadzone(1.9e-4, p), 0.0);
    EXPECT_EQ(backlash_deadzone(-2e-4, p), 0.0);
    EXPECT_NEAR(backlash_deadzone(5e-4, p), 3e-4, 1e-19);
    EXPECT_NEAR(backlash_deadzone(-7e-4, p), -5e-4, 1e-19);
    EXPECT_TRUE(std::isnan(backlash_deadzone(std::nan(""), p)));
}

// The compliance model reads zero torque inside the band and eq. (8) of the
// torsion beyond it outside.
TEST(EffectsBacklash, ComplianceModelIsZeroInsideTheBand) {
    Parameters p;
    p.backlash = 3e-4;
    const double theta_l = 0.2;
    for (double torsion : {-1.4e-4, -5e-5, 0.0, 1e-4, 1.49e-4}) {
        // No current, no kinematic error: dtheta_f is the total torsion.
        Parameters q = p;
        q.al1 = q.bl1 = q.aw1 = q.bw1 = q.aw2 = q.bw2 = 0.0;
        const ComplianceEstimate c = compliance_estimate(0.0, q.N * (theta_l + torsion), theta_l, q);
        ASSERT_TRUE(c.valid);
        EXPECT_NEAR(c.dtheta_f, torsion, 1e-15);  // dtheta_f stays eq. (4)'s torsion
        EXPECT_EQ(c.tau, 0.0) << torsion;
    }
    const Parameters paper;
    for (double torsion : {-6e-4, 2e-4, 9e-4}) {
        const double dtheta_f = compliance_estimate(0.0, p.N * (theta_l + torsion), theta_l, p).dtheta_f;
        double expected = 0.0;
        ASSERT_TRUE(flexspline_torque(dtheta_f - std::copysign(1.5e-4, dtheta_f), paper, &expected));
        EXPECT_NEAR(compliance_estimate(0.0, p.N * (theta_l + torsion), theta_l, p).tau, expected, 1e-12);
    }
}

TEST(EffectsBacklash, TransmittedTorqueTakesUpTheBandFirst) {
    Parameters p;
    p.backlash = 2e-3;
    double tau = 1.0;
    for (double y : {-1e-3, -3e-4, 0.0, 5e-4, 1e-3}) {
        ASSERT_TRUE(transmitted_torque(y, p, &tau));
        EXPECT_EQ(tau, 0.0) << y;
    }
    for (double T : {-20.0, -0.5, 0.01, 3.0, 15.0}) {
        const double y = chain_torsion(T, p) + std::copysign(1e-3, T);
        ASSERT_TRUE(transmitted_torque(y, p, &tau));
        EXPECT_NEAR(tau, T, 1e-9 * (1.0 + std::fabs(T)));
    }
}

// A free joint (no gravity, no damping coupling) driven from rest: the link
// does not move at all while the motor crosses the band, then follows.
TEST(EffectsBacklash, LinkStaysStillWhileTheMotorCrossesTheBand) {
    Parameters p;
    p.motor_counts = p.link_counts = 0.0;
    p.mgl = 0.0;
    p.Fc = p.Bm = 0.0;
    p.backlash = 4e-3;  // the motor travels N*b/2 = 0.2 rad before it touches
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    const double theta_l0 = j.state()(2);
    int touched = -1;
    for (int k = 0; k < 60; ++k) {
        ASSERT_TRUE(j.advance(1e-3, {0.5, 0.0}));
        const PlantState& x = j.state();
        const double elastic = total_torsion(x(0), x(2), p) - kinematic_error(x(0), x(2), p);
        // (After the first contact the link may bounce off and fly inside the band.)
        if (touched < 0 && std::fabs(elastic) <= 0.5 * p.backlash) {
            EXPECT_EQ(j.state()(3), 0.0) << "t = " << (k + 1) << " ms";
            EXPECT_EQ(j.state()(2), theta_l0);
            EXPECT_EQ(j.outputs().tau_joint, 0.0);
        } else if (touched < 0) {
            touched = k;
        }
    }
    // Motor alone: theta_m = Kt*i/Jm * t^2/2 reaches 0.2 rad at ~19 ms.
    EXPECT_GT(touched, 14);
    EXPECT_LT(touched, 25);
    EXPECT_GT(j.state()(2), theta_l0 + 1e-4);  // then the link follows
    EXPECT_GT(j.state()(3), 0.0);
}

TEST(EffectsBacklash, PlantStartsLoadedOnTheRightSide) {
    Parameters p;
    p.backlash = 1e-3;
    p.theta_l0 = 0.6;
    for (double tau_ext : {-8.0, 0.0, 3.0}) {
        JointPlant j(p);
        ASSERT_TRUE(j.initialize(tau_ext));
        double tau = 0.0;
        ASSERT_TRUE(j.joint_torque(j.state(), &tau));
        EXPECT_NEAR(tau, p.mgl * std::sin(p.theta_l0) + tau_ext, 1e-9);
        // At rest it stays (the link is held by the transmission).
        PlantFullState dx;
        ASSERT_TRUE(j.derivative(j.full_state(), 0.0, {0.0, tau_ext}, &dx, nullptr));
        EXPECT_NEAR(dx(3), 0.0, 1e-8);
    }
}

// Inside the band the Jacobian has no stiffness: the rows of the
// accelerations do not depend on the angles through the transmission.
TEST(EffectsBacklash, JacobianHasNoStiffnessInsideTheBand) {
    Parameters p;
    p.backlash = 1e-3;
    p.mgl = 0.0;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    PlantFullState dx;
    PlantJacobian J;
    ASSERT_TRUE(j.derivative(j.full_state(), 0.0, {0.0, 0.0}, &dx, &J));
    EXPECT_EQ(J(1, 0), 0.0);
    EXPECT_EQ(J(1, 2), 0.0);
    EXPECT_EQ(J(3, 0), 0.0);
    EXPECT_EQ(J(3, 2), 0.0);
}

}  // namespace
}  // namespace hdjoint
