#pragma once
// Motor-side friction of eq. (2): tau_fm (Coulomb, smoothed so the model stays
// differentiable through zero speed) plus viscous Bm*omega_m; and, beyond the
// paper (each off by default), a Stribeck rise Fs at low speed, a friction
// level drifting with time, a torque constant warming up, cogging torque on
// the motor and link friction.
#include <algorithm>
#include <cmath>

#include "parameters.h"

namespace hdjoint {

// Scale of the Coulomb+Stribeck friction t seconds after the start of a run:
// the linear drift hypothesis (1 + Fc_drift*t), held at >= 0 so friction
// never drives the motor. Exactly 1 when Fc_drift = 0.
inline double friction_drift_scale(double t, const Parameters& p) {
    return p.Fc_drift == 0.0 ? 1.0 : std::max(0.0, 1.0 + p.Fc_drift * t);
}

// The plant's scale: the drift times an exponential warm-up
// 1 + thermal_gain*(1 - exp(-t/thermal_tc)) (the truth the drift hypothesis
// approximates).
inline double plant_friction_scale(double t, const Parameters& p) {
    double s = friction_drift_scale(t, p);
    if (p.thermal_gain != 0.0) s *= 1.0 - p.thermal_gain * std::expm1(-t / p.thermal_tc);
    return s;
}

// The Coulomb+Stribeck level g(omega) = Fc + Fs*exp(-(omega/omega_s)^2) and its derivative.
inline double friction_level(double omega_m, const Parameters& p) {
    if (p.Fs == 0.0) return p.Fc;
    const double r = omega_m / p.omega_s;
    return p.Fc + p.Fs * std::exp(-r * r);
}
inline double friction_level_slope(double omega_m, const Parameters& p) {
    if (p.Fs == 0.0) return 0.0;
    const double r = omega_m / p.omega_s;
    return -2.0 * r / p.omega_s * p.Fs * std::exp(-r * r);
}

// tau_fm = scale * g(omega) * tanh(omega/omega_fc).
inline double coulomb_friction(double omega_m, const Parameters& p, double scale = 1.0) {
    return scale * (friction_level(omega_m, p) * std::tanh(omega_m / p.omega_fc));
}
inline double coulomb_friction_slope(double omega_m, const Parameters& p, double scale = 1.0) {
    const double c = std::cosh(omega_m / p.omega_fc);
    double slope = friction_level(omega_m, p) / (p.omega_fc * c * c);
    if (p.Fs != 0.0) slope += friction_level_slope(omega_m, p) * std::tanh(omega_m / p.omega_fc);
    return scale * slope;
}

inline double motor_friction(double omega_m, const Parameters& p, double scale = 1.0) {
    return coulomb_friction(omega_m, p, scale) + p.Bm * omega_m;
}

// Cogging (torque ripple) on the motor: cog_a*cos(n*theta_m) + cog_b*sin(n*theta_m).
inline bool cogging_on(const Parameters& p) { return p.cog_a != 0.0 || p.cog_b != 0.0; }
inline double cogging_torque(double theta_m, const Parameters& p) {
    const double w = p.cog_order * theta_m;
    return p.cog_a * std::cos(w) + p.cog_b * std::sin(w);
}
inline double cogging_slope(double theta_m, const Parameters& p) {
    const double w = p.cog_order * theta_m;
    return p.cog_order * (-p.cog_a * std::sin(w) + p.cog_b * std::cos(w));
}

// Scale of the torque constant t seconds after the start of a run, the
// lumped first-order warm-up 1 + Kt_warmup*(1 - exp(-t/Kt_warmup_tc)):
// Kt is proportional to the magnets' remanence Br, and sintered NdFeB grades
// lose 0.09-0.12 %/K of it (reversible temperature coefficient of Br, magnet
// grade data sheets), so Kt falls as the motor warms; the single thermal node
// of motor catalogues (one thermal time constant) makes the warm-up exponential.
// Exactly 1 when Kt_warmup = 0.
inline double torque_constant_scale(double t, const Parameters& p) {
    return p.Kt_warmup == 0.0 ? 1.0 : 1.0 - p.Kt_warmup * std::expm1(-t / p.Kt_warmup_tc);
}

// The motor's electromagnetic torque Kt(t)*i_m at t seconds into the run,
// plus cogging when it is on.
inline double motor_torque(double i_m, double theta_m, double t, const Parameters& p) {
    double torque = p.Kt * torque_constant_scale(t, p) * i_m;
    if (cogging_on(p)) torque += cogging_torque(theta_m, p);
    return torque;
}

// Link-side Coulomb friction, smoothed over its own link speed omega_fl
// (the link's bearings and seals, not the motor's): Fl*tanh(omega_l/omega_fl).
inline double link_friction(double omega_l, const Parameters& p) {
    return p.Fl * std::tanh(omega_l / p.omega_fl);
}
inline double link_friction_slope(double omega_l, const Parameters& p) {
    const double c = std::cosh(omega_l / p.omega_fl);
    return p.Fl / (p.omega_fl * c * c);
}

}  // namespace hdjoint
