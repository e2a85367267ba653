// Beyond the paper: the extra kinematic-error harmonics ke_m1/ke_m2 (on
// theta_m) and ke_l1/ke_l2 (on theta_l).
#include <gtest/gtest.h>

#include <cmath>

#include "joint_plant.h"
#include "parameters.h"
#include "torque_estimator.h"
#include "transmission.h"

namespace hdjoint {
namespace {

Parameters with_harmonics() {
    Parameters p;
    p.ke_m1_order = 1.0;
    p.ke_m1_a = 3e-5;
    p.ke_m1_b = -2e-5;
    p.ke_m2_order = 3.0;
    p.ke_m2_a = 1e-5;
    p.ke_m2_b = 4e-5;
    p.ke_l1_order = 2.0;
    p.ke_l1_a = -5e-5;
    p.ke_l1_b = 2.5e-5;
    p.ke_l2_order = 7.0;
    p.ke_l2_a = 1.5e-5;
    p.ke_l2_b = -1e-5;
    return p;
}

TEST(EffectsKinematic, HarmonicsAddToTheta_err) {
    const Parameters paper;
    const Parameters p = with_harmonics();
    for (double theta_m : {-40.0, -1.3, 0.0, 0.7, 123.4}) {
        for (double theta_l : {-1.0, 0.0, 0.35, 2.9}) {
            const double extra = p.ke_m1_a * std::cos(p.ke_m1_order * theta_m) +
                                 p.ke_m1_b * std::sin(p.ke_m1_order * theta_m) +
                                 p.ke_m2_a * std::cos(p.ke_m2_order * theta_m) +
                                 p.ke_m2_b * std::sin(p.ke_m2_order * theta_m) +
                                 p.ke_l1_a * std::cos(p.ke_l1_order * theta_l) +
                                 p.ke_l1_b * std::sin(p.ke_l1_order * theta_l) +
                                 p.ke_l2_a * std::cos(p.ke_l2_order * theta_l) +
                                 p.ke_l2_b * std::sin(p.ke_l2_order * theta_l);
            EXPECT_NEAR(kinematic_error(theta_m, theta_l, p), kinematic_error(theta_m, theta_l, paper) + extra,
                        1e-18);
        }
    }
}

TEST(EffectsKinematic, GradientAndCurvatureMatchFiniteDifferences) {
    const Parameters p = with_harmonics();
    const double h = 1e-5;
    for (double theta_m : {-3.0, 0.1, 17.0}) {
        for (double theta_l : {-0.4, 0.0, 1.2}) {
            double gm = 0.0, gl = 0.0, cm = 0.0, cl = 0.0;
            kinematic_error_gradient(theta_m, theta_l, p, &gm, &gl);
            kinematic_error_curvature(theta_m, theta_l, p, &cm, &cl);
            const double fd_m = (kinematic_error(theta_m + h, theta_l, p) - kinematic_error(theta_m - h, theta_l, p)) / (2 * h);
            const double fd_l = (kinematic_error(theta_m, theta_l + h, p) - kinematic_error(theta_m, theta_l - h, p)) / (2 * h);
            EXPECT_NEAR(gm, fd_m, 1e-9);
            EXPECT_NEAR(gl, fd_l, 1e-9);
            double gm_p, gm_m, gl_p, gl_m, unused;
            kinematic_error_gradient(theta_m + h, theta_l, p, &gm_p, &unused);
            kinematic_error_gradient(theta_m - h, theta_l, p, &gm_m, &unused);
            kinematic_error_gradient(theta_m, theta_l + h, p, &unused, &gl_p);
            kinematic_error_gradient(theta_m, theta_l - h, p, &unused, &gl_m);
            EXPECT_NEAR(cm, (gm_p - gm_m) / (2 * h), 1e-7);
            EXPECT_NEAR(cl, (gl_p - gl_m) / (2 * h), 1e-7);
        }
    }
}

// Zero amplitudes switch a harmonic off whatever its order: the model is the
// paper's, bit for bit.
TEST(EffectsKinematic, ZeroAmplitudesAreBitIdenticalToThePaper) {
    const Parameters paper;
    Parameters p;
    p.ke_m1_order = 5.0;
    p.ke_m2_order = 11.0;
    p.ke_l1_order = 0.5;
    p.ke_l2_order = 900.0;
    for (double theta_m : {-40.0, 0.0, 0.7}) {
        for (double theta_l : {-1.0, 0.35}) {
            EXPECT_EQ(kinematic_error(theta_m, theta_l, p), kinematic_error(theta_m, theta_l, paper));
            double a, b, c, d;
            kinematic_error_gradient(theta_m, theta_l, p, &a, &b);
            kinematic_error_gradient(theta_m, theta_l, paper, &c, &d);
            EXPECT_EQ(a, c);
            EXPECT_EQ(b, d);
        }
    }
    TorqueEstimator e1(paper), e2(p);
    for (int k = 0; k < 200; ++k) {
        const EstimatorInputs in{0.5 * std::sin(0.1 * k), 3.0 * std::sin(0.02 * k) + 0.001, 0.03 * std::sin(0.02 * k)};
        e1.step(in);
        e2.step(in);
        ASSERT_EQ(e1.save_state(), e2.save_state()) << "sample " << k;
    }
}

// The estimator's compliance model removes the harmonic: a joint whose
// encoders show only the harmonic (no load) reads zero torque when the
// harmonic is in the model.
TEST(EffectsKinematic, ComplianceModelRemovesTheHarmonic) {
    Parameters p = with_harmonics();
    for (double theta_m : {0.0, 1.0, 2.0, 5.0, 9.0}) {
        const double theta_l = 0.3;
        // theta_m/N - theta_l = theta_err: zero flexspline torsion.
        double tm = theta_m;
        for (int it = 0; it < 50; ++it) tm = p.N * (theta_l + kinematic_error(tm, theta_l, p));
        const ComplianceEstimate c = compliance_estimate(0.0, tm, theta_l, p);
        ASSERT_TRUE(c.valid);
        EXPECT_NEAR(c.tau, 0.0, 1e-9);
    }
}

// The plant starts in equilibrium with the harmonics in its kinematic error.
TEST(EffectsKinematic, PlantEquilibriumIncludesTheHarmonics) {
    Parameters p = with_harmonics();
    p.theta_l0 = 0.7;
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    double tau = 0.0;
    ASSERT_TRUE(j.joint_torque(j.state(), &tau));
    EXPECT_NEAR(tau, p.mgl * std::sin(p.theta_l0), 1e-9);
}

}  // namespace
}  // namespace hdjoint
