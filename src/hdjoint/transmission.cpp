#include "transmission.h"

#include <cmath>

namespace hdjoint {

namespace {
constexpr double kHalfPi = 1.5707963267948966;
// Below this the atan/exp laws are replaced by their linear limits.
constexpr double kLinearLimit = 1e-12;

double sign(double x) { return (x > 0.0) - (x < 0.0); }

// The extra kinematic-error harmonics a*cos(n*angle) + b*sin(n*angle). A
// harmonic with both amplitudes zero is skipped, not added as 0: the default
// model then costs and computes exactly what the paper's does.
struct Harmonic {
    double order, a, b;
    bool on() const { return a != 0.0 || b != 0.0; }
};
struct Harmonics {
    Harmonic h[2];
    // The sum (derivative 0), or its first (1) or second (2) derivative by the angle.
    double operator()(double angle, int derivative) const {
        double sum = 0.0;
        for (const Harmonic& k : h) {
            if (!k.on()) continue;
            const double c = std::cos(k.order * angle), s = std::sin(k.order * angle);
            if (derivative == 0) sum += k.a * c + k.b * s;
            else if (derivative == 1) sum += k.order * (-k.a * s + k.b * c);
            else sum -= k.order * k.order * (k.a * c + k.b * s);
        }
        return sum;
    }
};
// Cheap tests first: the default model never builds the tables.
bool motor_harmonics_on(const Parameters& p) {
    return p.ke_m1_a != 0.0 || p.ke_m1_b != 0.0 || p.ke_m2_a != 0.0 || p.ke_m2_b != 0.0;
}
bool link_harmonics_on(const Parameters& p) {
    return p.ke_l1_a != 0.0 || p.ke_l1_b != 0.0 || p.ke_l2_a != 0.0 || p.ke_l2_b != 0.0;
}
Harmonics motor_harmonics(const Parameters& p) {
    return {{{p.ke_m1_order, p.ke_m1_a, p.ke_m1_b}, {p.ke_m2_order, p.ke_m2_a, p.ke_m2_b}}};
}
Harmonics link_harmonics(const Parameters& p) {
    return {{{p.ke_l1_order, p.ke_l1_a, p.ke_l1_b}, {p.ke_l2_order, p.ke_l2_a, p.ke_l2_b}}};
}
}  // namespace

double total_torsion(double theta_m, double theta_l, const Parameters& p) {
    return theta_m / p.N - theta_l;
}

double kinematic_error(double theta_m, double theta_l, const Parameters& p) {
    const double l = p.omega_l * theta_l;
    const double w = p.omega_w * theta_m;
    double e = p.a0 + p.al1 * std::cos(l) + p.bl1 * std::sin(l) + p.aw1 * std::cos(w) +
               p.bw1 * std::sin(w) + p.aw2 * std::cos(2.0 * w) + p.bw2 * std::sin(2.0 * w);
    if (motor_harmonics_on(p)) e += motor_harmonics(p)(theta_m, 0);
    if (link_harmonics_on(p)) e += link_harmonics(p)(theta_l, 0);
    return e;
}

void kinematic_error_gradient(double theta_m, double theta_l, const Parameters& p, double* d_theta_m,
                              double* d_theta_l) {
    const double l = p.omega_l * theta_l;
    const double w = p.omega_w * theta_m;
    *d_theta_l = p.omega_l * (-p.al1 * std::sin(l) + p.bl1 * std::cos(l));
    *d_theta_m = p.omega_w * (-p.aw1 * std::sin(w) + p.bw1 * std::cos(w) +
                              2.0 * (-p.aw2 * std::sin(2.0 * w) + p.bw2 * std::cos(2.0 * w)));
    if (motor_harmonics_on(p)) *d_theta_m += motor_harmonics(p)(theta_m, 1);
    if (link_harmonics_on(p)) *d_theta_l += link_harmonics(p)(theta_l, 1);
}

void kinematic_error_curvature(double theta_m, double theta_l, const Parameters& p, double* dd_theta_m,
                               double* dd_theta_l) {
    const double l = p.omega_l * theta_l;
    const double w = p.omega_w * theta_m;
    *dd_theta_l = -p.omega_l * p.omega_l * (p.al1 * std::cos(l) + p.bl1 * std::sin(l));
    *dd_theta_m = -p.omega_w * p.omega_w *
                  (p.aw1 * std::cos(w) + p.bw1 * std::sin(w) +
                   4.0 * (p.aw2 * std::cos(2.0 * w) + p.bw2 * std::sin(2.0 * w)));
    *dd_theta_m += motor_harmonics(p)(theta_m, 2);
    *dd_theta_l += link_harmonics(p)(theta_l, 2);
}

double elastic_torsion_rate(double theta_m, double omega_m, double theta_l, double omega_l, const Parameters& p) {
    double dk_dm = 0.0, dk_dl = 0.0;
    kinematic_error_gradient(theta_m, theta_l, p, &dk_dm, &dk_dl);
    return omega_m / p.N - omega_l - dk_dm * omega_m - dk_dl * omega_l;
}

void elastic_torsion_rate_gradient(double theta_m, double omega_m, double theta_l, double omega_l,
                                   const Parameters& p, double d[4]) {
    double dk_dm = 0.0, dk_dl = 0.0;
    kinematic_error_gradient(theta_m, theta_l, p, &dk_dm, &dk_dl);
    elastic_torsion_rate_gradient(theta_m, omega_m, theta_l, omega_l, p, dk_dm, dk_dl, d);
}

void elastic_torsion_rate_gradient(double theta_m, double omega_m, double theta_l, double omega_l,
                                   const Parameters& p, double dk_dm, double dk_dl, double d[4]) {
    double dd_m = 0.0, dd_l = 0.0;
    kinematic_error_curvature(theta_m, theta_l, p, &dd_m, &dd_l);
    d[0] = -dd_m * omega_m;
    d[1] = 1.0 / p.N - dk_dm;
    d[2] = -dd_l * omega_l;
    d[3] = -1.0 - dk_dl;
}

double wave_generator_torsion(double tau_w, const Parameters& p) {
    if (p.Cw < kLinearLimit) return tau_w / (p.N * p.Kw);
    return sign(tau_w) / (p.Cw * p.N * p.Kw) * (-std::expm1(-p.Cw * std::fabs(tau_w)));
}

double wave_generator_compliance(double tau_w, const Parameters& p) {
    if (p.Cw < kLinearLimit) return 1.0 / (p.N * p.Kw);
    return std::exp(-p.Cw * std::fabs(tau_w)) / (p.N * p.Kw);
}

double flexspline_compliance(double tau_f, const Parameters& p) {
    const double c = p.Cf * tau_f;
    return 1.0 / (p.Kf * (1.0 + c * c));
}

bool flexspline_torque(double dtheta_f, const Parameters& p, double* tau_f) {
    if (p.Cf < kLinearLimit) {
        *tau_f = p.Kf * dtheta_f;
        return std::isfinite(*tau_f);
    }
    const double arg = p.Cf * p.Kf * dtheta_f;
    if (!(std::fabs(arg) < kHalfPi)) return false;
    *tau_f = std::tan(arg) / p.Cf;
    return std::isfinite(*tau_f);
}

ComplianceEstimate compliance_estimate(double i_m, double theta_m, double theta_l, const Parameters& p) {
    ComplianceEstimate e;
    if (p.wg_load > 0.0) return loaded_wave_generator_estimate(i_m, theta_m, theta_l, p);
    e.dtheta_f = total_torsion(theta_m, theta_l, p) - wave_generator_torsion(p.Kt * i_m, p) -
                 kinematic_error(theta_m, theta_l, p);
    e.valid = flexspline_torque(backlash_deadzone(e.dtheta_f, p), p, &e.tau);
    return e;
}

// With wg_load = w > 0 the wave generator carries (1-w)*Kt*i_m + w*tau/N, so
// the torque solves tau = f(tau) = eq8(deadzone(y - wg((1-w)*Kt*i_m + w*tau/N))).
// f changes with tau by -w*wg'/(N*eq8'^-1), about -0.1 for real joints: the
// fixed point is a contraction, and a Newton step on tau - f(tau) (its
// derivative is known in closed form) reaches round-off in 3-4 evaluations
// instead of the plain iteration's ~15: this runs for every sample of every
// diagnosis fit.
ComplianceEstimate loaded_wave_generator_estimate(double i_m, double theta_m, double theta_l, const Parameters& p) {
    ComplianceEstimate e;
    const double y = total_torsion(theta_m, theta_l, p) - kinematic_error(theta_m, theta_l, p);
    const double motor_part = (1.0 - p.wg_load) * p.Kt * i_m, gain = p.wg_load / p.N;
    double tau = 0.0;
    for (int it = 0; it < 100; ++it) {
        const double tau_w = motor_part + gain * tau;
        e.dtheta_f = y - wave_generator_torsion(tau_w, p);
        double next = 0.0;
        if (!flexspline_torque(backlash_deadzone(e.dtheta_f, p), p, &next)) return e;
        if (std::fabs(next - tau) <= 1e-13 * (1.0 + std::fabs(next))) {
            e.tau = next;
            e.dtheta_f = y - wave_generator_torsion(motor_part + gain * next, p);
            e.valid = std::isfinite(next);
            return e;
        }
        const double df = in_backlash(e.dtheta_f, p)
                              ? 0.0
                              : -gain * wave_generator_compliance(tau_w, p) / flexspline_compliance(next, p);
        // Newton on tau - f(tau); the plain step when the slope is unusable.
        const double newton = tau - (tau - next) / (1.0 - df);
        tau = (std::isfinite(newton) && df < 0.5) ? newton : next;
    }
    return e;  // no convergence: reported as a singular torsion
}

bool transmitted_torque(double elastic_torsion, const Parameters& p, double* tau) {
    if (!std::isfinite(elastic_torsion)) return false;  // NaN would fall through to "zero torque"
    const double y = backlash_deadzone(elastic_torsion, p);
    auto residual = [&](double t) { return flexspline_torsion(t, p) + wave_generator_torsion(t / p.N, p) - y; };
    // Bracket: the residual is odd-symmetric in shape and increasing; a
    // torque reaching the asymptote cannot be exceeded.
    double lo = 0.0, hi = 0.0;
    if (y > 0.0) {
        hi = 1.0;
        while (residual(hi) < 0.0) {
            hi *= 2.0;
            if (hi > 1e12) return false;
        }
    } else if (y < 0.0) {
        lo = -1.0;
        while (residual(lo) > 0.0) {
            lo *= 2.0;
            if (lo < -1e12) return false;
        }
    } else {
        *tau = 0.0;
        return true;
    }
    // Newton from the flexspline-only guess, falling back to bisection
    // whenever a step leaves the bracket.
    double t = 0.0;
    if (!flexspline_torque(y, p, &t) || t <= lo || t >= hi) t = 0.5 * (lo + hi);
    for (int it = 0; it < 200; ++it) {
        const double r = residual(t);
        if (r == 0.0) break;
        if (r > 0.0) hi = t; else lo = t;
        const double slope = flexspline_compliance(t, p) + wave_generator_compliance(t / p.N, p) / p.N;
        double next = t - r / slope;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (std::fabs(next - t) <= 1e-15 * (1.0 + std::fabs(t))) {
            t = next;
            break;
        }
        t = next;
    }
    *tau = t;
    return std::isfinite(t);
}

}  // namespace hdjoint
