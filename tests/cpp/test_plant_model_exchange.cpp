// The plant as Model Exchange sees it (HarmonicDriveJoint's FMU): a solver
// places the state and the clock, asks for the derivative, and watches the
// backlash's contact edges through the event indicators.
#include <gtest/gtest.h>

#include <cmath>

#include "joint_plant.h"
#include "parameters.h"
#include "transmission.h"

namespace hdjoint {
namespace {

// The elastic torsion of a state with no kinematic error: theta_m/N - theta_l.
Parameters without_kinematic_error() {
    Parameters p;
    p.a0 = p.al1 = p.bl1 = p.aw1 = p.bw1 = p.aw2 = p.bw2 = 0.0;
    return p;
}

TEST(PlantModelExchange, SetStateAndTimeRoundTrip) {
    JointPlant plant(Parameters{});
    ASSERT_TRUE(plant.initialize(0.0));
    PlantFullState x;
    x << 1.0, 2.0, 0.01, 0.02, 0.0, 0.0, 0.0;
    plant.set_full_state(x);
    plant.set_time(0.5);
    EXPECT_EQ(plant.full_state(), x);
    EXPECT_EQ(plant.time(), 0.5);
    // The derivative at the placed state is the right-hand side ROS2 integrates.
    PlantFullState a, b;
    ASSERT_TRUE(plant.derivative(x, 0.5, {0.3, 0.0}, &a, nullptr));
    ASSERT_TRUE(plant.derivative(plant.full_state(), plant.time(), {0.3, 0.0}, &b, nullptr));
    EXPECT_EQ(a, b);
    EXPECT_TRUE(plant.physical(x));
}

// Beyond the atan law's asymptote no torque explains the torsion: the
// right-hand side fails (the integrator retries its substep in halves, then
// reports a singular torsion) and the state is not physical, which Model
// Exchange refuses.
TEST(PlantModelExchange, BeyondTheAsymptoteTheStateIsNotPhysical) {
    const Parameters p = without_kinematic_error();
    JointPlant plant(p);
    ASSERT_TRUE(plant.initialize(0.0));
    const double asymptote = M_PI / (2.0 * p.Cf * p.Kf);
    PlantFullState x = PlantFullState::Zero();
    for (double torsion : {0.5 * asymptote, -0.5 * asymptote, 2.0 * asymptote, -2.0 * asymptote}) {
        x(0) = p.N * torsion;
        const bool inside = std::fabs(torsion) < asymptote;  // the wave generator adds 4 % at most
        PlantFullState dx;
        double elastic = 0.0;
        EXPECT_EQ(plant.derivative(x, 0.0, {0.0, 0.0}, &dx, nullptr), inside) << torsion;
        EXPECT_EQ(plant.physical(x, &elastic), inside) << torsion;
        EXPECT_NEAR(elastic, torsion, 1e-12) << torsion;
        plant.set_full_state(x);
        EXPECT_EQ(std::isnan(plant.outputs().tau_joint), !inside) << torsion;
    }
    x(0) = std::nan("");
    EXPECT_FALSE(plant.physical(x));
}

TEST(PlantModelExchange, EventIndicatorsCrossZeroAtTheBacklashEdges) {
    Parameters p = without_kinematic_error();
    JointPlant off(p);
    ASSERT_TRUE(off.initialize(0.0));
    EXPECT_EQ(off.event_indicators(), (Vector<2>() << 1.0, 1.0).finished());  // no backlash: constant
    p.backlash = 4e-4;
    JointPlant plant(p);
    ASSERT_TRUE(plant.initialize(0.0));
    auto at = [&](double torsion) {
        PlantFullState x = PlantFullState::Zero();
        x(0) = p.N * torsion;
        plant.set_full_state(x);
        return plant.event_indicators();
    };
    EXPECT_LT(at(1.9e-4)(0), 0.0);
    EXPECT_GT(at(2.1e-4)(0), 0.0);  // the teeth close on the positive side
    EXPECT_GT(at(-1.9e-4)(1), 0.0);
    EXPECT_LT(at(-2.1e-4)(1), 0.0);  // ... and on the negative side
    EXPECT_NEAR(at(2e-4)(0), 0.0, 1e-15);
}

}  // namespace
}  // namespace hdjoint
