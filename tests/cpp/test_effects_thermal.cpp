// Beyond the paper: the torque constant's warm-up (Kt_warmup, Kt_warmup_tc),
// the Kt form of thermal_drift: Kt(t) = Kt*(1 + g*(1 - exp(-t/tc))).
#include <gtest/gtest.h>

#include <cmath>

#include "friction.h"
#include "joint_plant.h"
#include "parameters.h"

namespace hdjoint {
namespace {

TEST(EffectsThermal, TorqueConstantScaleIsTheFirstOrderWarmUp) {
    Parameters p;
    EXPECT_EQ(torque_constant_scale(1.0e3, p), 1.0);  // off by default: the paper's constant Kt
    p.Kt_warmup = -0.04;
    p.Kt_warmup_tc = 15.0;
    EXPECT_EQ(torque_constant_scale(0.0, p), 1.0);  // cold at the start of the run
    EXPECT_NEAR(torque_constant_scale(15.0, p), 1.0 - 0.04 * (1.0 - std::exp(-1.0)), 1e-15);
    EXPECT_NEAR(torque_constant_scale(1.0e4, p), 0.96, 1e-15);  // t >> tc: 1 + g
    // Monotone from 1 to 1 + g.
    double previous = 1.0;
    for (double t = 0.5; t < 100.0; t += 0.5) {
        const double s = torque_constant_scale(t, p);
        EXPECT_LT(s, previous);
        EXPECT_GT(s, 0.96);
        previous = s;
    }
}

TEST(EffectsThermal, MotorTorqueScalesWithTheCurrentNotTheMotion) {
    Parameters p;
    p.Kt_warmup = -0.05;
    p.Kt_warmup_tc = 2.0;
    const double cold = motor_torque(1.5, 0.3, 0.0, p), warm = motor_torque(1.5, 0.3, 2.0, p);
    EXPECT_DOUBLE_EQ(cold, p.Kt * 1.5);
    EXPECT_NEAR(warm / cold, 1.0 - 0.05 * (1.0 - std::exp(-1.0)), 1e-14);
    EXPECT_EQ(motor_torque(0.0, 0.3, 2.0, p), 0.0);  // no current, no drift (friction's drift needs motion)
}

TEST(EffectsThermal, PlantAccelerationFollowsTheWarmUp) {
    Parameters p;
    p.Kt_warmup = -0.05;
    p.Kt_warmup_tc = 2.0;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    const double i_m = 2.0;
    PlantFullState cold, warm;
    ASSERT_TRUE(j.derivative(j.full_state(), 0.0, {i_m, 0.0}, &cold, nullptr));
    ASSERT_TRUE(j.derivative(j.full_state(), 4.0, {i_m, 0.0}, &warm, nullptr));
    // Only the motor torque changes: d omega_m/dt drops by Kt*g*(1 - e^-2)*i_m/Jm.
    const double expected = p.Kt * p.Kt_warmup * (1.0 - std::exp(-2.0)) * i_m / p.Jm;
    EXPECT_NEAR(warm(1) - cold(1), expected, 1e-9 * std::fabs(expected));
    EXPECT_EQ(warm(3), cold(3));
}

}  // namespace
}  // namespace hdjoint
