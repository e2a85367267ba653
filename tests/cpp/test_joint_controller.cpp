// JointController (the controller of the co-simulated JTF system): its
// parameter table, sampling rule, JTF switch, limit and state.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "joint_controller.h"

namespace hdjoint {
namespace {

TEST(JointController, TableDefaultsAreValidAndNamesUnique) {
    ControllerParameters p;
    EXPECT_FALSE(validate(p).has_value());
    const ControllerParameterInfo* t = controller_parameter_table();
    for (std::size_t i = 0; i < controller_parameter_count(); ++i) {
        EXPECT_EQ(p.*(t[i].member), t[i].default_value) << t[i].name;
        EXPECT_LE(t[i].min, t[i].default_value) << t[i].name;
        EXPECT_GE(t[i].max, t[i].default_value) << t[i].name;
        for (std::size_t j = 0; j < i; ++j) EXPECT_NE(std::string(t[i].name), t[j].name);
    }
}

TEST(JointController, ValidateNamesTheBadParameter) {
    ControllerParameters p;
    p.jtf = 0.5;
    ASSERT_TRUE(validate(p).has_value());
    EXPECT_NE(validate(p)->find("jtf"), std::string::npos);
    p = ControllerParameters();
    p.kp = std::nan("");
    ASSERT_TRUE(validate(p).has_value());
    EXPECT_NE(validate(p)->find("kp"), std::string::npos);
}

// One sample per Ts whatever the partition: noisy steps, a 3 ms step, two half steps.
TEST(JointController, SamplesOnItsOwnGrid) {
    ControllerParameters p;
    const ControllerInputs in{10.0, 0.1, 1.0};
    JointController a(p), b(p);
    for (int k = 0; k < 6; ++k) a.advance(k * 1e-3, 1e-3, in);
    double t = 0.0;
    const double noisy = 0.0009999999999976694;
    for (int k = 0; k < 2; ++k, t += noisy) b.advance(t, noisy, in);
    b.advance(t, 0.003, in);
    t += 0.003;
    b.advance(t, 0.0005, in);
    b.advance(t + 0.0005, 0.0005, in);
    EXPECT_EQ(a.save_state(), b.save_state()) << "a different number of samples was taken";
    EXPECT_EQ(a.outputs().i_m, b.outputs().i_m);
}

TEST(JointController, JtfOffIgnoresTheTorqueAndTheLimitHolds) {
    ControllerParameters p;
    p.jtf = 0.0;
    JointController a(p), b(p);
    a.advance(0.0, 0.01, {1.0, 0.0, 0.0});
    b.advance(0.0, 0.01, {1.0, 0.0, 50.0});
    EXPECT_EQ(a.outputs().i_m, b.outputs().i_m);
    p.jtf = 1.0;
    JointController c(p);
    c.advance(0.0, 0.01, {-1000.0, 0.0, -50.0});
    EXPECT_EQ(c.outputs().i_m, p.i_max);
}

TEST(JointController, SavedStateContinuesIdentically) {
    ControllerParameters p;
    JointController a(p);
    for (int k = 0; k < 50; ++k) a.advance(k * 1e-3, 1e-3, {0.01 * k, 1e-4 * k, std::sin(0.1 * k)});
    JointController b(p, 5.0);
    ASSERT_TRUE(b.load_state(a.save_state()));
    for (int k = 50; k < 80; ++k) {
        const ControllerInputs in{0.02 * k, 2e-4 * k, std::cos(0.1 * k)};
        a.advance(k * 1e-3, 1e-3, in);
        b.advance(k * 1e-3, 1e-3, in);
        EXPECT_EQ(a.outputs().i_m, b.outputs().i_m);
        EXPECT_EQ(a.outputs().tau_d, b.outputs().tau_d);
    }
    EXPECT_FALSE(b.load_state({1.0, 2.0}));
}

}  // namespace
}  // namespace hdjoint
