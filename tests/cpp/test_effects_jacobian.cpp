// The plant's analytic Jacobian against central finite differences of its
// right-hand side, with every beyond-the-paper effect switched on, on random
// states.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "joint_plant.h"
#include "parameters.h"
#include "transmission.h"

namespace hdjoint {
namespace {

Parameters every_effect_on() {
    Parameters p;
    p.Df = 0.4;
    p.ke_m1_a = 2e-5;
    p.ke_m1_b = -1e-5;
    p.ke_m2_a = 1e-5;
    p.ke_l1_b = 3e-5;
    p.ke_l2_a = -2e-5;
    p.Fs = 0.01;
    p.omega_s = 6.0;
    p.Fc_drift = 0.005;
    p.thermal_gain = 0.4;
    p.thermal_tc = 3.0;
    p.cog_a = 0.003;
    p.cog_b = -0.002;
    p.Fl = 0.8;
    p.backlash = 2e-4;
    p.hys_H = 0.3;
    p.hys_sigma = 5e3;
    p.bw_A = 2e3;
    p.bw_beta = 3e3;
    p.bw_gamma = 1e3;
    p.lugre_sigma0 = 1e4;
    p.lugre_sigma1 = 0.05;
    return p;
}

// Each column of J against (f(x + h e_j) - f(x - h e_j)) / 2h, relative to
// the column's size.
void expect_jacobian_matches(const JointPlant& j, const PlantFullState& x, double t, const PlantInputs& in) {
    PlantFullState f0;
    PlantJacobian J;
    ASSERT_TRUE(j.derivative(x, t, in, &f0, &J));
    for (int c = 0; c < x.size(); ++c) {
        const double h = 1e-6 * (1.0 + std::fabs(x(c)));
        PlantFullState xp = x, xm = x, fp, fm;
        xp(c) += h;
        xm(c) -= h;
        ASSERT_TRUE(j.derivative(xp, t, in, &fp, nullptr));
        ASSERT_TRUE(j.derivative(xm, t, in, &fm, nullptr));
        const PlantFullState fd = (fp - fm) / (2.0 * h);
        const double scale = std::max(fd.cwiseAbs().maxCoeff(), J.col(c).cwiseAbs().maxCoeff());
        for (int r = 0; r < x.size(); ++r)
            EXPECT_NEAR(J(r, c), fd(r), 1e-5 * scale + 1e-9) << "J(" << r << ", " << c << ")";
    }
}

TEST(EffectsJacobian, MatchesFiniteDifferencesWithEveryEffectOn) {
    const Parameters p = every_effect_on();
    JointPlant j(p);
    ASSERT_TRUE(j.initialize(0.0));
    std::mt19937 rng(20180707);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int checked = 0;
    for (int trial = 0; trial < 40; ++trial) {
        PlantFullState x = j.full_state();
        const double theta_l = 2.0 * u(rng);
        const double torsion = 4e-4 * u(rng);  // a few N.m
        x(0) = p.N * (theta_l + torsion);
        x(1) = 40.0 * u(rng);
        x(2) = theta_l;
        x(3) = 0.3 * u(rng);
        x(4) = p.hys_H * u(rng);
        x(5) = 0.5 * u(rng);
        x(6) = 2.0 * p.Fc / p.lugre_sigma0 * u(rng);
        const double t = 10.0 * (u(rng) + 1.0);
        // Away from the corners where a derivative does not exist: the edge of
        // the backlash dead zone, and the signs of the torsion rate, the motor
        // speed and the Bouc-Wen torque.
        const double elastic = total_torsion(x(0), x(2), p) - kinematic_error(x(0), x(2), p);
        double gm = 0.0, gl = 0.0;
        kinematic_error_gradient(x(0), x(2), p, &gm, &gl);
        const double rate = x(1) / p.N - x(3) - gm * x(1) - gl * x(3);
        if (std::fabs(std::fabs(elastic) - 0.5 * p.backlash) < 2e-5 || std::fabs(rate) < 1e-3 ||
            std::fabs(x(1)) < 1e-3 || std::fabs(x(5)) < 1e-3)
            continue;
        SCOPED_TRACE(trial);
        expect_jacobian_matches(j, x, t, {2.0 * u(rng), 0.5 * u(rng)});
        ++checked;
    }
    EXPECT_GE(checked, 20);
}

}  // namespace
}  // namespace hdjoint
