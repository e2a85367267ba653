// The compliance chain of eq. (3)-(8) with the sign conventions of CONTRACT.md.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "parameters.h"
#include "transmission.h"

namespace hdjoint {
namespace {

constexpr double kPi = 3.141592653589793;

std::vector<double> torque_range() {
    std::vector<double> t;
    for (double m : {1e-6, 1e-3, 0.1, 0.5, 1.0, 3.9, 12.0, 50.0, 200.0, 1e3, 1e4}) {
        t.push_back(m);
        t.push_back(-m);
    }
    t.push_back(0.0);
    return t;
}

// The largest elastic torsion any torque can produce: both laws saturate.
// Infinite when either law is linear (Cf = 0 or Cw = 0).
double max_elastic_torsion(const Parameters& p) {
    if (p.Cf == 0.0 || p.Cw == 0.0) return HUGE_VAL;
    return kPi / (2.0 * p.Cf * p.Kf) + 1.0 / (p.Cw * p.N * p.Kw);
}

double chain_torsion(double tau, const Parameters& p) {
    return flexspline_torsion(tau, p) + wave_generator_torsion(tau / p.N, p);
}

TEST(Transmission, TotalTorsionSignConvention) {
    Parameters p;
    // Ideal gear theta_l = theta_m / N: no torsion.
    EXPECT_NEAR(total_torsion(150.0, 1.5, p), 0.0, 1e-15);
    // Motor ahead of the link: positive torsion.
    EXPECT_NEAR(total_torsion(1.0, 0.0, p), 0.01, 1e-15);
    EXPECT_NEAR(total_torsion(0.0, 0.02, p), -0.02, 1e-15);
}

TEST(Transmission, FlexspineTorqueInvertsTorsion) {
    for (double Cf : {0.0645, 0.5, 3.0, 1e-6}) {
        Parameters p;
        p.Cf = Cf;
        for (double tau : torque_range()) {
            const double dtheta_f = flexspline_torsion(tau, p);
            double back = std::nan("");
            ASSERT_TRUE(flexspline_torque(dtheta_f, p, &back)) << "Cf=" << Cf << " tau=" << tau;
            // The atan law loses relative precision as Cf*tau grows (tan near
            // its pole amplifies the rounding of dtheta_f by ~(Cf*tau)).
            const double amplification = 1.0 + std::fabs(Cf * tau);
            EXPECT_NEAR(back, tau, 1e-12 * std::fabs(tau) * amplification + 1e-300)
                << "Cf=" << Cf << " tau=" << tau;
        }
    }
}

TEST(Transmission, FlexsplineTorsionSignAndMonotonicity) {
    Parameters p;
    double previous = -1e300;
    for (double tau = -100.0; tau <= 100.0; tau += 0.5) {
        const double s = flexspline_torsion(tau, p);
        EXPECT_GT(s, previous) << tau;
        previous = s;
        EXPECT_EQ(s, -flexspline_torsion(-tau, p));
    }
    EXPECT_GT(flexspline_torsion(1.0, p), 0.0);
    // Eq. (5) at a hand-computed point: atan(0.0645*12)/(0.0645*1e4).
    EXPECT_NEAR(flexspline_torsion(12.0, p), std::atan(0.774) / 645.0, 1e-18);
    // Tangent stiffness rises from Kf at zero torque to Kf*(1+(Cf*tau)^2).
    EXPECT_NEAR(1.0 / flexspline_compliance(0.0, p), p.Kf, 1e-9);
    EXPECT_NEAR(1.0 / flexspline_compliance(12.0, p), p.Kf * (1.0 + 0.774 * 0.774), 1e-8);
}

TEST(Transmission, FlexsplineLinearLimit) {
    Parameters p;
    for (double tau : torque_range()) {
        // Cf = 0 is exactly linear.
        p.Cf = 0.0;
        EXPECT_EQ(flexspline_torsion(tau, p), tau / p.Kf);
        double back = 0.0;
        ASSERT_TRUE(flexspline_torque(tau / p.Kf, p, &back));
        EXPECT_NEAR(back, tau, 1e-12 * std::fabs(tau));
        // Tiny Cf tends to it continuously (atan(x)/x = 1 - x^2/3 + ...).
        for (double Cf : {1e-9, 1e-11, 1e-13}) {
            p.Cf = Cf;
            // The relative deviation is (Cf*tau)^2/3 (atan) and (Cf*Kf*dtheta)^2/3 (tan).
            const double rel = std::pow(Cf * tau, 2) / 3.0;
            EXPECT_NEAR(flexspline_torsion(tau, p), tau / p.Kf, (1.01 * rel + 1e-14) * std::fabs(tau / p.Kf) + 1e-300)
                << Cf << " " << tau;
            ASSERT_TRUE(flexspline_torque(tau / p.Kf, p, &back));
            EXPECT_NEAR(back, tau, (1.01 * rel + 1e-14) * std::fabs(tau) + 1e-300) << Cf << " " << tau;
        }
    }
}

TEST(Transmission, FlexsplineTorqueFailsAtAndBeyondTheAsymptote) {
    Parameters p;
    const double half_pi = kPi / 2.0;
    // The smallest torsion whose computed Cf*Kf*dtheta_f reaches pi/2.
    double at = half_pi / (p.Cf * p.Kf);
    while (p.Cf * p.Kf * at < half_pi) at = std::nextafter(at, 1.0);
    double tau = 123.0;
    EXPECT_FALSE(flexspline_torque(at, p, &tau));
    EXPECT_FALSE(flexspline_torque(-at, p, &tau));
    EXPECT_FALSE(flexspline_torque(1.5 * at, p, &tau));
    EXPECT_FALSE(flexspline_torque(-10.0 * at, p, &tau));
    EXPECT_FALSE(flexspline_torque(std::nan(""), p, &tau));
    EXPECT_FALSE(flexspline_torque(HUGE_VAL, p, &tau));
    // Cf*Kf = 1: the torsion pi/2 (as a double) is exactly at the asymptote.
    Parameters unit;
    unit.Cf = 1.0;
    unit.Kf = 1.0;
    EXPECT_FALSE(flexspline_torque(half_pi, unit, &tau));
    EXPECT_FALSE(flexspline_torque(-half_pi, unit, &tau));
    ASSERT_TRUE(flexspline_torque(std::nextafter(half_pi, 0.0), unit, &tau));
    EXPECT_GT(tau, 1e15);
    // Just below it: a (large) finite torque of the right sign.
    const double below = 0.999 * at;
    ASSERT_TRUE(flexspline_torque(below, p, &tau));
    EXPECT_GT(tau, 100.0 / p.Cf);
    ASSERT_TRUE(flexspline_torque(-below, p, &tau));
    EXPECT_LT(tau, -100.0 / p.Cf);
}

TEST(Transmission, WaveGeneratorTorsionOddSaturatingAndLinearLimit) {
    Parameters p;  // Cw = 10, Kw = 10, N = 100
    const double saturation = 1.0 / (p.Cw * p.N * p.Kw);
    double previous = -1e300;
    for (double tau = -5.0; tau <= 5.0; tau += 0.01) {
        const double w = wave_generator_torsion(tau, p);
        EXPECT_EQ(w, -wave_generator_torsion(-tau, p)) << tau;  // odd
        EXPECT_LE(std::fabs(w), saturation) << tau;
        EXPECT_GE(w, previous) << tau;
        previous = w;
    }
    EXPECT_EQ(wave_generator_torsion(0.0, p), 0.0);
    // Eq. (4) at a hand-computed point.
    EXPECT_NEAR(wave_generator_torsion(0.05, p), (1.0 - std::exp(-0.5)) / 1e4, 1e-18);
    EXPECT_NEAR(wave_generator_torsion(-0.05, p), -(1.0 - std::exp(-0.5)) / 1e4, 1e-18);
    // Saturates at 1/(Cw*N*Kw).
    EXPECT_NEAR(wave_generator_torsion(100.0, p), saturation, 1e-15 * saturation);
    EXPECT_NEAR(wave_generator_torsion(-1e6, p), -saturation, 1e-15 * saturation);
    // Small torques: linear with slope 1/(N*Kw).
    // (relative deviation Cw*tau/2 = 5e-9 here)
    EXPECT_NEAR(wave_generator_torsion(1e-9, p), 1e-9 / (p.N * p.Kw), 1e-8 * 1e-9 / (p.N * p.Kw));
    EXPECT_LT(std::fabs(wave_generator_torsion(1.0, p)), 0.7 / (p.N * p.Kw));  // and bends away at 1 N.m
    EXPECT_NEAR(wave_generator_compliance(0.0, p), 1.0 / (p.N * p.Kw), 1e-18);
    // Cw = 0 is the linear law.
    p.Cw = 0.0;
    for (double tau : {-3.0, -0.1, 0.0, 0.2, 7.0}) {
        EXPECT_EQ(wave_generator_torsion(tau, p), tau / (p.N * p.Kw));
        EXPECT_EQ(wave_generator_compliance(tau, p), 1.0 / (p.N * p.Kw));
    }
    // ... and tiny Cw tends to it.
    p.Cw = 1e-9;
    EXPECT_NEAR(wave_generator_torsion(7.0, p), 7.0 / (p.N * p.Kw), 1e-8 * 7.0 / (p.N * p.Kw));
}

TEST(Transmission, ComplianceDerivativesMatchFiniteDifferences) {
    Parameters p;
    for (double tau : {-20.0, -1.0, -0.03, 0.04, 0.5, 8.0, 30.0}) {
        const double h = 1e-5 * std::max(1.0, std::fabs(tau));
        const double fd = (flexspline_torsion(tau + h, p) - flexspline_torsion(tau - h, p)) / (2.0 * h);
        EXPECT_NEAR(flexspline_compliance(tau, p), fd, 1e-7 * fd) << tau;
        const double fdw = (wave_generator_torsion(tau + h, p) - wave_generator_torsion(tau - h, p)) / (2.0 * h);
        EXPECT_NEAR(wave_generator_compliance(tau, p), fdw, 1e-6 * fdw + 1e-18) << tau;
    }
}

TEST(Transmission, KinematicErrorMatchesEquation7) {
    Parameters p;
    p.a0 = 1e-3;
    const double tm = 0.7, tl = 0.3;
    const double expected = 1e-3 + p.al1 * std::cos(p.omega_l * tl) + p.bl1 * std::sin(p.omega_l * tl) +
                            p.aw1 * std::cos(p.omega_w * tm) + p.bw1 * std::sin(p.omega_w * tm) +
                            p.aw2 * std::cos(2 * p.omega_w * tm) + p.bw2 * std::sin(2 * p.omega_w * tm);
    EXPECT_NEAR(kinematic_error(tm, tl, p), expected, 1e-18);
}

TEST(Transmission, KinematicErrorGradientMatchesFiniteDifferences) {
    Parameters p;
    p.omega_l = 3.0;  // exercise the orders too
    p.omega_w = 2.0;
    p.a0 = 0.01;
    for (double tm : {-40.0, -0.3, 0.0, 1.1, 17.0, 628.0}) {
        for (double tl : {-0.4, 0.0, 0.25, 2.9}) {
            double dm = 0.0, dl = 0.0;
            kinematic_error_gradient(tm, tl, p, &dm, &dl);
            const double h = 1e-5;
            const double fdm = (kinematic_error(tm + h, tl, p) - kinematic_error(tm - h, tl, p)) / (2 * h);
            const double fdl = (kinematic_error(tm, tl + h, p) - kinematic_error(tm, tl - h, p)) / (2 * h);
            // Truncation ~ h^2 * omega^3 * amplitude, rounding ~ 1e-16 * a0 / h.
            EXPECT_NEAR(dm, fdm, 1e-9) << tm << " " << tl;
            EXPECT_NEAR(dl, fdl, 1e-9) << tm << " " << tl;
        }
    }
    // Each harmonic on its own, to be sure none is dropped.
    for (double Parameters::*amp : {&Parameters::al1, &Parameters::bl1, &Parameters::aw1, &Parameters::bw1,
                                    &Parameters::aw2, &Parameters::bw2}) {
        Parameters q;
        q.al1 = q.bl1 = q.aw1 = q.bw1 = q.aw2 = q.bw2 = 0.0;
        q.*amp = 0.005;
        for (double tm : {0.2, 1.3}) {
            double dm = 0.0, dl = 0.0;
            kinematic_error_gradient(tm, 0.4, q, &dm, &dl);
            const double h = 1e-5;
            const double fdm = (kinematic_error(tm + h, 0.4, q) - kinematic_error(tm - h, 0.4, q)) / (2 * h);
            const double fdl = (kinematic_error(tm, 0.4 + h, q) - kinematic_error(tm, 0.4 - h, q)) / (2 * h);
            EXPECT_NEAR(dm, fdm, 1e-10);
            EXPECT_NEAR(dl, fdl, 1e-10);
        }
    }
}

TEST(Transmission, TransmittedTorqueSolvesItsEquation) {
    for (double Cf : {0.0645, 0.0, 1.0}) {
        for (double Cw : {10.0, 0.0}) {
            Parameters p;
            p.Cf = Cf;
            p.Cw = Cw;
            const double m = max_elastic_torsion(p);
            std::vector<double> torsions;
            for (double y : {0.0, 1e-9, -1e-9, 1e-6, -1e-6, 1e-4, -1e-4, 1.3e-3, -1.3e-3, 2e-3, -2e-3})
                if (std::fabs(y) < 0.9 * m) torsions.push_back(y);
            if (std::isfinite(m)) {
                // Near the asymptote: 99.9% and 1 - 1e-6 of the largest producible torsion.
                for (double f : {0.999, 1.0 - 1e-6}) {
                    torsions.push_back(f * m);
                    torsions.push_back(-f * m);
                }
            }
            for (double y : torsions) {
                double tau = std::nan("");
                ASSERT_TRUE(transmitted_torque(y, p, &tau)) << "Cf=" << Cf << " Cw=" << Cw << " y=" << y;
                ASSERT_TRUE(std::isfinite(tau));
                EXPECT_NEAR(chain_torsion(tau, p), y, 1e-12 * std::fabs(y) + 1e-18)
                    << "Cf=" << Cf << " Cw=" << Cw << " y=" << y << " tau=" << tau;
                if (y > 0.0) {
                    EXPECT_GT(tau, 0.0);
                } else if (y < 0.0) {
                    EXPECT_LT(tau, 0.0);
                } else {
                    EXPECT_EQ(tau, 0.0);
                }
            }
        }
    }
}

TEST(Transmission, TransmittedTorqueRoundTripsTorques) {
    Parameters p;
    for (double tau : torque_range()) {
        if (std::fabs(tau) > 1e3) continue;  // beyond ~1e3 N.m the torsion no longer resolves the torque
        double back = std::nan("");
        ASSERT_TRUE(transmitted_torque(chain_torsion(tau, p), p, &back)) << tau;
        EXPECT_NEAR(back, tau, 1e-9 * (1.0 + std::fabs(tau)) * (1.0 + std::pow(p.Cf * tau, 2))) << tau;
    }
}

TEST(Transmission, TransmittedTorqueFailsBeyondAnyTorque) {
    Parameters p;
    const double m = max_elastic_torsion(p);
    double tau = 0.0;
    for (double f : {1.0 + 1e-9, 1.01, 2.0, 100.0}) {
        EXPECT_FALSE(transmitted_torque(f * m, p, &tau)) << f;
        EXPECT_FALSE(transmitted_torque(-f * m, p, &tau)) << f;
    }
    // Past the flexspline's own asymptote but within what the wave generator adds: still solvable.
    const double y = kPi / (2.0 * p.Cf * p.Kf) + 0.5 / (p.Cw * p.N * p.Kw);
    ASSERT_TRUE(transmitted_torque(y, p, &tau));
    EXPECT_NEAR(chain_torsion(tau, p), y, 1e-12 * y);
}

// Regression (fixed in 7135e36): a NaN torsion fell through both `y > 0` and
// `y < 0` into the `y == 0` branch and was reported as a valid zero torque,
// although the function's contract is to return false outside the model's
// domain (JointPlant::joint_torque/outputs() inherited it).
TEST(Transmission, TransmittedTorqueRejectsNaNTorsion) {
    Parameters p;
    double tau = 123.0;
    EXPECT_FALSE(transmitted_torque(std::nan(""), p, &tau)) << "NaN torsion accepted, tau = " << tau;
    EXPECT_FALSE(transmitted_torque(HUGE_VAL, p, &tau));
    EXPECT_FALSE(transmitted_torque(-HUGE_VAL, p, &tau));
}

TEST(Transmission, ComplianceEstimateMatchesHandComputedEquations) {
    Parameters p;  // defaults, kinematic error on
    p.a0 = 2e-4;
    struct Point {
        double i_m, theta_m, theta_l;
    };
    for (const Point& pt : {Point{1.0, 10.0, 0.0998}, Point{-0.5, -3.0, -0.0301}, Point{0.2, 31.4, 0.3139}}) {
        // eq. (6)
        const double dtheta = pt.theta_m / p.N - pt.theta_l;
        // eq. (4), tau_w = Kt*i_m
        const double tw = p.Kt * pt.i_m;
        const double wg = (tw > 0 ? 1.0 : -1.0) / (p.Cw * p.N * p.Kw) * (1.0 - std::exp(-p.Cw * std::fabs(tw)));
        // eq. (7), theta_w = theta_m
        const double l = p.omega_l * pt.theta_l, w = p.omega_w * pt.theta_m;
        const double err = p.a0 + p.al1 * std::cos(l) + p.bl1 * std::sin(l) + p.aw1 * std::cos(w) +
                           p.bw1 * std::sin(w) + p.aw2 * std::cos(2 * w) + p.bw2 * std::sin(2 * w);
        // eq. (3), (8)
        const double dtheta_f = dtheta - wg - err;
        const double tau = std::tan(p.Cf * p.Kf * dtheta_f) / p.Cf;

        const ComplianceEstimate e = compliance_estimate(pt.i_m, pt.theta_m, pt.theta_l, p);
        ASSERT_TRUE(e.valid);
        EXPECT_NEAR(e.dtheta_f, dtheta_f, 1e-15);
        EXPECT_NEAR(e.tau, tau, 1e-10 * (1.0 + std::fabs(tau)));
        EXPECT_GT(std::fabs(tau), 0.05);  // the points are not trivially zero
    }
}

TEST(Transmission, ComplianceEstimateSingularTorsionIsInvalid) {
    Parameters p;
    const ComplianceEstimate e = compliance_estimate(0.0, 1000.0 * p.N, 0.0, p);
    EXPECT_FALSE(e.valid);
    EXPECT_GT(std::fabs(p.Cf * p.Kf * e.dtheta_f), kPi / 2.0);
}

}  // namespace
}  // namespace hdjoint
