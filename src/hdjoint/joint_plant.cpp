#include "joint_plant.h"

#include <cmath>
#include <sstream>

#include "friction.h"
#include "transmission.h"

namespace hdjoint {

using namespace plant_state;

namespace {
constexpr double kTwoPi = 6.283185307179586;
// Floor of the LuGre friction level g(w), N.m: keeps z/g finite when Fc = Fs = 0.
constexpr double kMinLuGreLevel = 1e-9;
// The LuGre law's |w| is regularised as sqrt(w^2 + eps^2), eps = this times
// omega_fc: a right-hand side that is smooth through rest keeps ROS2's
// linearisation valid when the motor sticks, where the stiff bristles would
// otherwise chatter across w = 0 and drift. The price is a creep of about
// eps under a torque below breakaway, 1000 times less than the tanh law's.
constexpr double kLuGreRest = 1e-3;
// ROS2's L-stable choice of gamma.
const double kGamma = 1.0 + 1.0 / std::sqrt(2.0);
}  // namespace

double quantise(double angle, double counts) {
    if (counts <= 0.0) return angle;
    const double resolution = kTwoPi / counts;
    return std::floor(angle / resolution) * resolution;
}

HDJ_DEFINE_SIGNAL_TABLE(plant_signals, PlantInputs, PlantOutputs, HDJ_PLANT_SIGNALS)

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
    bool converged = false;
    for (int it = 0; it < 100 && !converged; ++it) {
        const double next = p_.N * (theta_l + kinematic_error(theta_m, theta_l, p_) + spring);
        converged = std::fabs(next - theta_m) <= 1e-14 * (1.0 + std::fabs(theta_m));
        theta_m = next;
    }
    if (!converged) {
        double dk_dm = 0.0, dk_dl = 0.0;
        kinematic_error_gradient(theta_m, theta_l, p_, &dk_dm, &dk_dl);
        if (message) {
            *message = "the kinematic error is too large to start from: N*d(theta_err)/d(theta_m) = " +
                       std::to_string(p_.N * dk_dm) +
                       " must stay well below 1 (the motor angle carrying the initial load is not unique); "
                       "reduce the amplitudes at motor-angle orders (aw1, bw1, aw2, bw2, ke_m*)";
        }
        return false;
    }
    x_ << theta_m, 0.0, theta_l, 0.0;
    z_.setZero();  // no hysteresis torque, relaxed bristles
    t_ = 0.0;
    double check = 0.0;
    if (!joint_torque(x_, &check)) {
        if (message) *message = "the initial state has a singular torsion";
        return false;
    }
    return true;
}

bool JointPlant::joint_torque(const PlantState& x, double* tau) const { return torque(x, z_, tau); }

bool JointPlant::torque(const PlantState& x, const Vector<3>& z, double* tau) const {
    const double elastic = total_torsion(x(kThetaM), x(kThetaL), p_) - kinematic_error(x(kThetaM), x(kThetaL), p_);
    double tau_f = 0.0;
    if (!transmitted_torque(elastic, p_, &tau_f)) return false;  // beyond the torsion asymptote: none
    // Damping of the deformation only (elastic_torsion_rate).
    if (p_.Df != 0.0) *tau = tau_f + p_.Df * elastic_torsion_rate(x(kThetaM), x(kOmegaM), x(kThetaL), x(kOmegaL), p_);
    else *tau = tau_f;
    if (p_.hys_H > 0.0) *tau += z(0);
    if (p_.bw_A > 0.0) *tau += z(1);
    return std::isfinite(*tau);
}

// Each law pulls its state back inside a bound (+-H, +-A/(beta + gamma),
// +-max g/sigma0) and never lets it grow beyond: a step is plausible when no
// state ends beyond both its bound and where it started.
bool JointPlant::within_bounds(const Vector<3>& z, double h) const {
    constexpr double kSlack = 1.01;
    auto fits = [&](int k, double bound) { return std::fabs(z(k)) <= kSlack * std::max(bound, std::fabs(z_(k))); };
    if (p_.hys_H > 0.0 && !fits(0, p_.hys_H)) return false;
    if (p_.bw_A > 0.0 && p_.bw_beta + p_.bw_gamma > 0.0 && !fits(1, p_.bw_A / (p_.bw_beta + p_.bw_gamma)))
        return false;
    if (p_.lugre_sigma0 > 0.0) {
        // The friction scale is monotone over a substep: its larger end bounds it.
        const double scale = std::max(plant_friction_scale(t_, p_), plant_friction_scale(t_ + h, p_));
        const double g_max = std::max((p_.Fc + p_.Fs) * scale, kMinLuGreLevel);
        if (!fits(2, g_max / p_.lugre_sigma0)) return false;
    }
    return true;
}

bool JointPlant::physical(const PlantFullState& x, double* elastic) const {
    if (elastic)
        *elastic = total_torsion(x(kThetaM), x(kThetaL), p_) - kinematic_error(x(kThetaM), x(kThetaL), p_);
    double tau = 0.0;
    return x.allFinite() && torque(x.head<4>(), x.tail<3>(), &tau);
}

PlantFullState JointPlant::full_state() const {
    PlantFullState x;
    x << x_, z_;
    return x;
}

bool JointPlant::derivative(const PlantFullState& x, double t, const PlantInputs& in, PlantFullState* dx,
                            PlantJacobian* J) const {
    return model<kPlantStates>(x, t, in, dx, J);
}

template <int S>
bool JointPlant::model(const Vector<S>& x, double t, const PlantInputs& in, Vector<S>* dx, Matrix<S>* J) const {
    static_assert(S == 4 || S == kPlantStates, "the plant has 4 mechanical and 3 effect states");
    constexpr bool kFull = S == kPlantStates;
    const double theta_m = x(kThetaM), omega_m = x(kOmegaM), theta_l = x(kThetaL), omega_l = x(kOmegaL);
    const double elastic = total_torsion(theta_m, theta_l, p_) - kinematic_error(theta_m, theta_l, p_);
    double tau_f = 0.0;
    if (!transmitted_torque(elastic, p_, &tau_f)) return false;
    const double scale = plant_friction_scale(t, p_);
    const bool dahl = kFull && p_.hys_H > 0.0, bouc_wen = kFull && p_.bw_A > 0.0;
    const bool lugre = kFull && p_.lugre_sigma0 > 0.0;

    // The rate of the elastic torsion (without the kinematic error's, which is
    // geometry): it drives the hysteresis states and the damping Df.
    double rate = 0.0;
    double friction = 0.0, level = 0.0, speed = 0.0, dz_lugre = 0.0;
    if (dahl || bouc_wen || p_.Df != 0.0) rate = elastic_torsion_rate(theta_m, omega_m, theta_l, omega_l, p_);
    double tau = tau_f + p_.Df * rate;
    if constexpr (kFull) {
        if (dahl) tau += x(4);
        if (bouc_wen) tau += x(5);
    }
    if (lugre) {
        // g(w) held above a floor: with no Coulomb level the bristles just stay at zero.
        level = std::max(friction_level(omega_m, p_) * scale, kMinLuGreLevel);
        speed = std::hypot(omega_m, kLuGreRest * p_.omega_fc);
        dz_lugre = omega_m - p_.lugre_sigma0 * speed * x(S - 1) / level;
        friction = p_.lugre_sigma0 * x(S - 1) + p_.lugre_sigma1 * dz_lugre + p_.Bm * omega_m;
    } else {
        friction = motor_friction(omega_m, p_, scale);
    }
    const double link_load = link_net_torque(tau, theta_l, omega_l, in.tau_ext, p_);

    (*dx)(0) = omega_m;
    (*dx)(1) = (motor_torque(in.i_m, theta_m, t, p_) - friction - tau / p_.N) / p_.Jm;
    (*dx)(2) = omega_l;
    (*dx)(3) = link_load / p_.Jl;
    if constexpr (kFull) {
        (*dx)(4) = dahl ? p_.hys_sigma * (rate - std::fabs(rate) * x(4) / p_.hys_H) : 0.0;
        (*dx)(5) = bouc_wen ? p_.bw_A * rate - p_.bw_beta * std::fabs(rate) * x(5) -
                                  p_.bw_gamma * rate * std::fabs(x(5))
                            : 0.0;
        (*dx)(6) = lugre ? dz_lugre : 0.0;
    }
    if (!dx->allFinite()) return false;
    if (!J) return true;

    // d tau_f / d elastic torsion = 1 / (total compliance of the chain).
    const double compliance = flexspline_compliance(tau_f, p_) + wave_generator_compliance(tau_f / p_.N, p_) / p_.N;
    const double stiffness = in_backlash(elastic, p_) ? 0.0 : 1.0 / compliance;  // slack: no stiffness
    // Gradient of the elastic torsion rate by [theta_m, omega_m, theta_l, omega_l]; d elastic / d theta_m is
    // drate[1] and d elastic / d theta_l is drate[3] (the rate is the elastic torsion's time derivative).
    double drate[4];
    elastic_torsion_rate_gradient(theta_m, omega_m, theta_l, omega_l, p_, drate);
    const double dtau_dtheta_m = stiffness * drate[1] + p_.Df * drate[0];
    const double dtau_dtheta_l = stiffness * drate[3] + p_.Df * drate[2];
    const double dtau_domega_m = p_.Df * drate[1];
    const double dtau_domega_l = p_.Df * drate[3];
    const double dfriction = lugre ? 0.0 : coulomb_friction_slope(omega_m, p_, scale) + p_.Bm;

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
    if constexpr (kFull) {
        // The hysteresis torques enter tau like the elastic torque.
        for (int k : {4, 5}) {
            if (!(k == 4 ? dahl : bouc_wen)) continue;
            (*J)(1, k) = -1.0 / (p_.N * p_.Jm);
            (*J)(3, k) = 1.0 / p_.Jl;
        }
        if (dahl || bouc_wen) {
            const double sign_rate = (rate > 0.0) - (rate < 0.0);
            if (dahl) {
                const double by_rate = p_.hys_sigma * (1.0 - sign_rate * x(4) / p_.hys_H);
                for (int c = 0; c < 4; ++c) (*J)(4, c) = by_rate * drate[c];
                (*J)(4, 4) = -p_.hys_sigma * std::fabs(rate) / p_.hys_H;
            }
            if (bouc_wen) {
                const double z = x(5);
                const double sign_z = (z > 0.0) - (z < 0.0);
                const double by_rate = p_.bw_A - p_.bw_beta * sign_rate * z - p_.bw_gamma * std::fabs(z);
                for (int c = 0; c < 4; ++c) (*J)(5, c) = by_rate * drate[c];
                (*J)(5, 5) = -p_.bw_beta * std::fabs(rate) - p_.bw_gamma * rate * sign_z;
            }
        }
        if (lugre) {
            // dz/dt = w - sigma0*|w|*z/g(w), F = sigma0*z + sigma1*dz/dt + Bm*w.
            const double z = x(6);
            const double dlevel = level > kMinLuGreLevel ? friction_level_slope(omega_m, p_) * scale : 0.0;
            const double ddz_dw =
                1.0 - p_.lugre_sigma0 * z * (omega_m / speed / level - speed * dlevel / (level * level));
            const double ddz_dz = -p_.lugre_sigma0 * speed / level;
            (*J)(6, 1) = ddz_dw;
            (*J)(6, 6) = ddz_dz;
            (*J)(1, 1) -= (p_.lugre_sigma1 * ddz_dw + p_.Bm) / p_.Jm;
            (*J)(1, 6) = -(p_.lugre_sigma0 + p_.lugre_sigma1 * ddz_dz) / p_.Jm;
        }
    }
    return J->allFinite();
}

template <int S>
bool JointPlant::ros2_step(double h, const PlantInputs& in, std::string* message) {
    Vector<S> x0, f0, f1;
    if constexpr (S == 4) x0 = x_;
    else x0 << x_, z_;
    Matrix<S> J;
    auto fail = [&](const char* what) {
        if (message) {
            std::ostringstream s;
            s.precision(17);
            s << what << " at theta_m = " << x_(kThetaM) << " rad, theta_l = " << x_(kThetaL)
              << " rad (i_m = " << in.i_m << " A, tau_ext = " << in.tau_ext << " N.m)";
            *message = s.str();
        }
        return false;
    };
    // Stages at t and t + h: ROS2 stays second order for a time-dependent
    // right-hand side without the df/dt term (it is order 2 for any Jacobian).
    if (!model<S>(x0, t_, in, &f0, &J)) return fail("singular torsion or non-finite state");
    const Eigen::PartialPivLU<Matrix<S>> W(Matrix<S>::Identity() - kGamma * h * J);
    const Vector<S> k1 = W.solve(f0);
    if (!model<S>(x0 + h * k1, t_ + h, in, &f1, nullptr)) return fail("singular torsion inside a substep");
    const Vector<S> k2 = W.solve(f1 - 2.0 * k1);
    const Vector<S> next = x0 + 1.5 * h * k1 + 0.5 * h * k2;
    if (!next.allFinite()) return fail("non-finite state");
    Vector<3> z_next = z_;
    if constexpr (S == kPlantStates) {
        z_next = next.template tail<3>();
        // A step that breaks what the exact laws guarantee has lost the stiff
        // dynamics: retried in halves.
        if (!within_bounds(z_next, h)) return fail("hysteresis or bristle state beyond its bound");
    }
    double tau = 0.0;  // reject a step that lands beyond the torsion asymptote, so it can be retried smaller
    if (!torque(next.template head<4>(), z_next, &tau)) return fail("singular torsion at the end of a substep");
    x_ = next.template head<4>();
    z_ = z_next;
    t_ += h;
    return true;
}

bool JointPlant::advance(double h, const PlantInputs& in, std::string* message) {
    if (!(h > 0.0)) return true;
    // Counted in double first: h/max_step can exceed any integer type.
    const double needed = std::max(1.0, std::ceil(h / p_.max_step - 1e-9));
    if (!(needed <= kMaxSubstepsPerAdvance)) {
        if (message) {
            std::ostringstream s;
            s.precision(17);
            s << "a step of h = " << h << " s needs " << needed << " substeps of max_step = " << p_.max_step
              << " s; at most " << kMaxSubstepsPerAdvance << " are allowed per step: split the step";
            *message = s.str();
        }
        return false;
    }
    const long substeps = static_cast<long>(needed);
    const double dt = h / static_cast<double>(substeps);
    for (long i = 0; i < substeps; ++i)
        if (!substep(dt, in, 0, message)) return false;
    return true;
}

// A substep whose stage leaves the model's domain (a violent transient
// overshooting the torsion asymptote) is retried as two halves, down to
// 1/1024 of a substep, before the plant reports failure.
bool JointPlant::substep(double h, const PlantInputs& in, int depth, std::string* message) {
    const PlantState before = x_;
    const Vector<3> z_before = z_;
    const bool ok = extra_states() ? ros2_step<kPlantStates>(h, in, depth == kMaxHalvings ? message : nullptr)
                                   : ros2_step<4>(h, in, depth == kMaxHalvings ? message : nullptr);
    if (ok) return true;
    x_ = before;  // a failed step leaves t_ alone
    z_ = z_before;
    if (depth == kMaxHalvings) return false;
    return substep(0.5 * h, in, depth + 1, message) && substep(0.5 * h, in, depth + 1, message);
}

PlantOutputs JointPlant::outputs() const {
    PlantOutputs o;
    o.theta_m = quantise(x_(kThetaM), p_.motor_counts);
    o.theta_l = quantise(x_(kThetaL), p_.link_counts);
    o.omega_m = x_(kOmegaM);
    o.omega_link = x_(kOmegaL);
    double tau = 0.0;
    o.tau_joint = torque(x_, z_, &tau) ? tau : std::nan("");
    return o;
}

Vector<JointPlant::kEventIndicators> JointPlant::event_indicators() const {
    Vector<kEventIndicators> z = Vector<kEventIndicators>::Ones();
    if (p_.backlash > 0.0) {
        const double elastic =
            total_torsion(x_(kThetaM), x_(kThetaL), p_) - kinematic_error(x_(kThetaM), x_(kThetaL), p_);
        z << elastic - 0.5 * p_.backlash, elastic + 0.5 * p_.backlash;
    }
    return z;
}

PlantInternals JointPlant::internals() const {
    PlantInternals r;
    r.friction_scale = plant_friction_scale(t_, p_);
    r.tau_friction = motor_friction(x_(kOmegaM), p_, r.friction_scale);
    if (cogging_on(p_)) r.tau_cogging = cogging_torque(x_(kThetaM), p_);
    if (p_.Fl != 0.0) r.tau_link_friction = link_friction(x_(kOmegaL), p_);
    if (p_.lugre_sigma0 > 0.0) {
        PlantFullState dx;
        r.tau_friction = derivative(full_state(), t_, {}, &dx, nullptr)
                             ? p_.lugre_sigma0 * z_(2) + p_.lugre_sigma1 * dx(6) + p_.Bm * x_(kOmegaM)
                             : std::nan("");
    }
    if (p_.hys_H > 0.0) r.z_dahl = z_(0);
    if (p_.bw_A > 0.0) r.z_bouc_wen = z_(1);
    if (p_.lugre_sigma0 > 0.0) r.z_lugre = z_(2);
    r.elastic_torsion = total_torsion(x_(kThetaM), x_(kThetaL), p_) - kinematic_error(x_(kThetaM), x_(kThetaL), p_);
    return r;
}

}  // namespace hdjoint
