#pragma once
// The harmonic drive's compliance chain, eq. (3)-(8), with the sign
// conventions of CONTRACT.md:
//   dtheta   = theta_m/N - theta_l                        (total torsion, eq. 6)
//   dtheta_f = dtheta - wg(tau_w) - theta_err             (eq. 3/4)
//   dtheta_f = atan(Cf*tau_f)/(Cf*Kf)                     (eq. 5)
//   tau_f    = tan(Cf*Kf*dtheta_f)/Cf                     (eq. 8)
#include <cmath>

#include "parameters.h"

namespace hdjoint {

// eq. (6): total torsion from the two encoder angles.
double total_torsion(double theta_m, double theta_l, const Parameters& p);

// eq. (7): kinematic error (theta_w is the motor angle theta_m), plus the
// extra harmonics ke_m*/ke_l* (beyond the paper, off by default), and its
// partial derivatives by theta_m and theta_l. The error is a sum of a
// function of theta_m and one of theta_l, so its mixed derivative is zero.
double kinematic_error(double theta_m, double theta_l, const Parameters& p);
void kinematic_error_gradient(double theta_m, double theta_l, const Parameters& p, double* d_theta_m,
                              double* d_theta_l);
void kinematic_error_curvature(double theta_m, double theta_l, const Parameters& p, double* dd_theta_m,
                               double* dd_theta_l);  // second derivatives

// The elastic torsion's rate: the total torsion's less the kinematic error's
// (gear geometry, not strain). It drives the structural damping Df and the
// hysteresis. Its gradient by [theta_m, omega_m, theta_l, omega_l] in d.
double elastic_torsion_rate(double theta_m, double omega_m, double theta_l, double omega_l, const Parameters& p);
void elastic_torsion_rate_gradient(double theta_m, double omega_m, double theta_l, double omega_l,
                                   const Parameters& p, double d[4]);
// The same, the kinematic error's gradient (kinematic_error_gradient) already at hand.
void elastic_torsion_rate_gradient(double theta_m, double omega_m, double theta_l, double omega_l,
                                   const Parameters& p, double dk_dm, double dk_dl, double d[4]);

// eq. (4): torsion of the wave generator seen at the output, for a motor-side torque tau_w.
double wave_generator_torsion(double tau_w, const Parameters& p);
double wave_generator_compliance(double tau_w, const Parameters& p);  // d wg / d tau_w

// eq. (5): flexspline torsion carrying tau_f, and its derivative.
inline double flexspline_torsion(double tau_f, double Cf, double Kf) {
    // Below Cf = 1e-12 the atan law is replaced by its linear limit.
    return Cf < 1e-12 ? tau_f / Kf : std::atan(Cf * tau_f) / (Cf * Kf);
}
inline double flexspline_torsion(double tau_f, const Parameters& p) { return flexspline_torsion(tau_f, p.Cf, p.Kf); }
double flexspline_compliance(double tau_f, const Parameters& p);  // d/dtau_f

// eq. (8): flexspline torque from its torsion. False when the torsion is
// beyond the atan law's asymptote (|Cf*Kf*dtheta_f| >= pi/2): no torque
// explains it, the caller reports a singular torsion.
bool flexspline_torque(double dtheta_f, const Parameters& p, double* tau_f);

// Lost motion (beyond the paper): a dead zone of total width b = backlash on
// the torsion, x - b/2 above b/2, x + b/2 below -b/2, 0 inside. The identity
// when backlash = 0.
inline double backlash_deadzone(double torsion, const Parameters& p) {
    if (p.backlash <= 0.0) return torsion;
    const double half = 0.5 * p.backlash;
    if (torsion > half) return torsion - half;
    if (torsion < -half) return torsion + half;
    return torsion == torsion ? 0.0 : torsion;  // NaN stays NaN
}
inline bool in_backlash(double torsion, const Parameters& p) {
    return p.backlash > 0.0 && std::fabs(torsion) <= 0.5 * p.backlash;
}

// The compliance-model estimate of eq. (3)-(8) with tau_w = Kt*i_m; with
// backlash, eq. (8) acts on the torsion beyond the dead zone.
struct ComplianceEstimate {
    double dtheta_f = 0.0;  // flexspline torsion, rad
    double tau = 0.0;       // joint torque, N.m
    bool valid = false;     // false: singular torsion, tau is meaningless
};
ComplianceEstimate compliance_estimate(double i_m, double theta_m, double theta_l, const Parameters& p);
// The same with the wave generator loaded by the transmitted torque (wg_load > 0).
ComplianceEstimate loaded_wave_generator_estimate(double i_m, double theta_m, double theta_l, const Parameters& p);

// The plant's transmitted torque: solves
//   dtheta - theta_err - b/2*sign(tau) = flexspline_torsion(tau) + wave_generator_torsion(tau/N)
// for tau (the wave generator carries the motor-side share tau/N; b the
// backlash, tau = 0 inside it). Both terms rise monotonically with tau, so
// the root is unique; safeguarded Newton. False when the torsion exceeds
// what any torque can produce.
bool transmitted_torque(double elastic_torsion, const Parameters& p, double* tau);

}  // namespace hdjoint
