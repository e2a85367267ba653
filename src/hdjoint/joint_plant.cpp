#include "joint_plant.h"

#include <cmath>
#include <sstream>

#include "friction.h"
#include "transmission.h"

namespace hdjoint {

namespace {
constexpr double kTwoPi = 6.283185307179586;
constexpr double kStateVersion = 2.0;
// ROS2's L-stable choice of gamma.
const double kGamma = 1.0 + 1.0 / std::sqrt(2.0);
}  // namespace

double quantise(double angle, double counts) {
    if (counts <= 0.0) return angle;
    const double resolution = kTwoPi / counts;
    return std::floor(angle / resolution) * resolution;
}

JointPlant::JointPlant(const Parameters& p) : p_(p) {}

bool JointPlant::initialize(double tau_ext, std::string* message) {
    const double theta_l = p_.theta_l0;
    const double tau = p_.mgl * std::sin(theta_l) + tau_ext;
    double spring = flexspline_torsion(tau, p_) + wave_generator_torsion(tau / p_.N, p_);
    // Backlash is taken up on the loaded side.
    if (p_.backlash > 0.0 && tau != 0.0) spring += std::copysign(0.5 * p_.backlash, tau);
    if (!std::isfinite(spring)) {
        if (message) *message = "no finite torsion carries the initial load torque";
        return false;
    }
    // theta_m = N*(theta_l + theta_err(theta_m, theta_l) + spring): a
    // contraction, since N*d(theta_err)/d(theta_m) is far below 1 for any
    // real harmonic drive; iterate to convergence.
    double theta_m = p_.N * (theta_l + spring);
    for (int it = 0; it < 100; ++it) {
        const double next = p_.N * (theta_l + kinematic_error(theta_m, theta_l, p_) + spring);
        const bool done = std::fabs(next - theta_m) <= 1e-14 * (1.0 + std::fabs(theta_m));
        theta_m = next;
        if (done) break;
    }
    x_ << theta_m, 0.0, theta_l, 0.0;
    t_ = 0.0;
    double check = 0.0;
    if (!joint_torque(x_, &check)) {
        if (message) *message = "the initial state has a singular torsion";
        return false;
    }
    return true;
}

bool JointPlant::joint_torque(const PlantState& x, double* tau) const {
    const double elastic = total_torsion(x(0), x(2), p_) - kinematic_error(x(0), x(2), p_);
    double tau_f = 0.0;
    if (!transmitted_torque(elastic, p_, &tau_f)) return false;
    *tau = tau_f + p_.Df * (x(1) / p_.N - x(3));
    return std::isfinite(*tau);
}

bool JointPlant::derivative(const PlantState& x, double t, const PlantInputs& in, PlantState* dx,
                            Matrix<4>* J) const {
    const double theta_m = x(0), omega_m = x(1), theta_l = x(2), omega_l = x(3);
    const double elastic = total_torsion(theta_m, theta_l, p_) - kinematic_error(theta_m, theta_l, p_);
    double tau_f = 0.0;
    if (!transmitted_torque(elastic, p_, &tau_f)) return false;
    const double tau = tau_f + p_.Df * (omega_m / p_.N - omega_l);
    const double scale = plant_friction_scale(t, p_);
    double link_load = tau - p_.Bl * omega_l - p_.mgl * std::sin(theta_l) - in.tau_ext;
    if (p_.Fl != 0.0) link_load -= link_friction(omega_l, p_);

    (*dx)(0) = omega_m;
    (*dx)(1) = (motor_torque(in.i_m, theta_m, p_) - motor_friction(omega_m, p_, scale) - tau / p_.N) / p_.Jm;
    (*dx)(2) = omega_l;
    (*dx)(3) = link_load / p_.Jl;
    if (!dx->allFinite()) return false;
    if (!J) return true;

    // d tau_f / d elastic torsion = 1 / (total compliance of the chain).
    const double compliance = flexspline_compliance(tau_f, p_) + wave_generator_compliance(tau_f / p_.N, p_) / p_.N;
    const double stiffness = in_backlash(elastic, p_) ? 0.0 : 1.0 / compliance;  // slack: no stiffness
    double dk_dm = 0.0, dk_dl = 0.0;
    kinematic_error_gradient(theta_m, theta_l, p_, &dk_dm, &dk_dl);
    const double dtau_dtheta_m = stiffness * (1.0 / p_.N - dk_dm);
    const double dtau_dtheta_l = stiffness * (-1.0 - dk_dl);
    const double dtau_domega_m = p_.Df / p_.N;
    const double dtau_domega_l = -p_.Df;
    const double dfriction = coulomb_friction_slope(omega_m, p_, scale) + p_.Bm;

    J->setZero();
    (*J)(0, 1) = 1.0;
    (*J)(1, 0) = -dtau_dtheta_m / (p_.N * p_.Jm);
    if (cogging_on(p_)) (*J)(1, 0) += cogging_slope(theta_m, p_) / p_.Jm;
    (*J)(1, 1) = (-dfriction - dtau_domega_m / p_.N) / p_.Jm;
    (*J)(1, 2) = -dtau_dtheta_l / (p_.N * p_.Jm);
    (*J)(1, 3) = -dtau_domega_l / (p_.N * p_.Jm);
    (*J)(2, 3) = 1.0;
    (*J)(3, 0) = dtau_dtheta_m / p_.Jl;
    (*J)(3, 1) = dtau_domega_m / p_.Jl;
    (*J)(3, 2) = (dtau_dtheta_l - p_.mgl * std::cos(theta_l)) / p_.Jl;
    (*J)(3, 3) = (dtau_domega_l - p_.Bl) / p_.Jl;
    if (p_.Fl != 0.0) (*J)(3, 3) -= link_friction_slope(omega_l, p_) / p_.Jl;
    return J->allFinite();
}

bool JointPlant::ros2_step(double h, const PlantInputs& in, std::string* message) {
    PlantState f0, f1;
    Matrix<4> J;
    auto fail = [&](const char* what) {
        if (message) {
            std::ostringstream s;
            s.precision(17);
            s << what << " at theta_m = " << x_(0) << " rad, theta_l = " << x_(2)
              << " rad (i_m = " << in.i_m << " A, tau_ext = " << in.tau_ext << " N.m)";
            *message = s.str();
        }
        return false;
    };
    // Stages at t and t + h: ROS2 stays second order for a time-dependent
    // right-hand side without the df/dt term (it is order 2 for any Jacobian).
    if (!derivative(x_, t_, in, &f0, &J)) return fail("singular torsion or non-finite state");
    const Eigen::PartialPivLU<Matrix<4>> W(Matrix<4>::Identity() - kGamma * h * J);
    const PlantState k1 = W.solve(f0);
    if (!derivative(x_ + h * k1, t_ + h, in, &f1, nullptr)) return fail("singular torsion inside a substep");
    const PlantState k2 = W.solve(f1 - 2.0 * k1);
    const PlantState next = x_ + 1.5 * h * k1 + 0.5 * h * k2;
    if (!next.allFinite()) return fail("non-finite state");
    double tau = 0.0;  // reject a step that lands beyond the torsion asymptote, so it can be retried smaller
    if (!joint_torque(next, &tau)) return fail("singular torsion at the end of a substep");
    x_ = next;
    t_ += h;
    return true;
}

bool JointPlant::advance(double h, const PlantInputs& in, std::string* message) {
    if (!(h > 0.0)) return true;
    const int substeps = std::max(1, static_cast<int>(std::ceil(h / p_.max_step - 1e-9)));
    const double dt = h / substeps;
    for (int i = 0; i < substeps; ++i)
        if (!substep(dt, in, 0, message)) return false;
    return true;
}

// A substep whose stage leaves the model's domain (a violent transient
// overshooting the torsion asymptote) is retried as two halves, down to
// 1/1024 of a substep, before the plant reports failure.
bool JointPlant::substep(double h, const PlantInputs& in, int depth, std::string* message) {
    const PlantState before = x_;
    if (ros2_step(h, in, depth == kMaxHalvings ? message : nullptr)) return true;
    x_ = before;  // a failed step leaves t_ alone
    if (depth == kMaxHalvings) return false;
    return substep(0.5 * h, in, depth + 1, message) && substep(0.5 * h, in, depth + 1, message);
}

PlantOutputs JointPlant::outputs() const {
    PlantOutputs o;
    o.theta_m = quantise(x_(0), p_.motor_counts);
    o.theta_l = quantise(x_(2), p_.link_counts);
    o.omega_m = x_(1);
    o.omega_l = x_(3);
    double tau = 0.0;
    o.tau_joint = joint_torque(x_, &tau) ? tau : std::nan("");
    return o;
}

PlantInternals JointPlant::internals() const {
    PlantInternals r;
    r.friction_scale = plant_friction_scale(t_, p_);
    r.tau_friction = motor_friction(x_(1), p_, r.friction_scale);
    if (cogging_on(p_)) r.tau_cogging = cogging_torque(x_(0), p_);
    if (p_.Fl != 0.0) r.tau_link_friction = link_friction(x_(3), p_);
    return r;
}

// [version, theta_m, omega_m, theta_l, omega_l, time]
std::vector<double> JointPlant::save_state() const { return {kStateVersion, x_(0), x_(1), x_(2), x_(3), t_}; }

bool JointPlant::load_state(const std::vector<double>& d) {
    if (d.size() != 6 || d[0] != kStateVersion) return false;
    x_ << d[1], d[2], d[3], d[4];
    t_ = d[5];
    return true;
}

}  // namespace hdjoint
