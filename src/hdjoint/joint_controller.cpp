#include "joint_controller.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace hdjoint {

namespace {
const ControllerParameterInfo kTable[] = {
#define HDJ_CONTROLLER_PARAMETER(name, unit, def, lo, hi, description) \
    {#name, unit, def, lo, hi, description, &ControllerParameters::name},
#include "controller_table.def"
#undef HDJ_CONTROLLER_PARAMETER
};
constexpr std::size_t kCount = sizeof(kTable) / sizeof(kTable[0]);
static_assert(kCount < 100, "parameter value references would collide with the FMU's inputs (100+)");
constexpr double kPi = 3.14159265358979323846;

// Smooth 0-to-1 rise over `rise` starting at 0 (a jump when rise is 0).
double smooth_step(double x, double rise) {
    if (x < 0.0) return 0.0;
    if (rise <= 0.0 || x >= rise) return 1.0;
    const double u = x / rise;
    return u * u * (3.0 - 2.0 * u);
}
}  // namespace

const ControllerParameterInfo* controller_parameter_table() { return kTable; }
std::size_t controller_parameter_count() { return kCount; }

std::optional<std::string> validate(const ControllerParameters& p) {
    std::ostringstream msg;
    msg.precision(17);
    for (const ControllerParameterInfo& info : kTable) {
        const double v = p.*(info.member);
        if (!std::isfinite(v) || v < info.min || v > info.max) {
            msg << "parameter " << info.name << " = " << v << " is outside its valid range [" << info.min << ", "
                << info.max << "] " << info.unit;
            return msg.str();
        }
    }
    if (p.jtf != 0.0 && p.jtf != 1.0) {
        msg << "parameter jtf = " << p.jtf << " must be 0 (position PD only) or 1 (joint torque feedback on tau_fb)";
        return msg.str();
    }
    return std::nullopt;
}

HDJ_DEFINE_SIGNAL_TABLE(controller_signals, ControllerInputs, ControllerOutputs, HDJ_CONTROLLER_SIGNALS)

JointController::JointController(const ControllerParameters& p, double start_time)
    : p_(p), clock_(start_time, p.Ts) {
    double omega_ref = 0.0;
    out_.theta_ref = reference(start_time, &omega_ref);
    out_.tau_ext = disturbance(start_time);
}

double JointController::reference(double t, double* omega_ref) const {
    // 1 - cos: the joint starts at rest at ref_offset with zero reference speed.
    const double w = 2.0 * kPi * p_.ref_frequency;
    if (omega_ref) *omega_ref = p_.ref_amplitude * w * std::sin(w * t);
    return p_.ref_offset + p_.ref_amplitude * (1.0 - std::cos(w * t));
}

double JointController::disturbance(double t) const {
    double d = p_.dist_step * smooth_step(t - p_.dist_on, p_.dist_rise);
    if (p_.dist_off > p_.dist_on) d -= p_.dist_step * smooth_step(t - p_.dist_off, p_.dist_rise);
    if (p_.dist_sine != 0.0) d += p_.dist_sine * std::sin(2.0 * kPi * p_.dist_frequency * t);
    return d;
}

bool JointController::advance(double t, double h, const ControllerInputs& in, std::string* message) {
    return clock_.run_until(t + h, [&](double t_k) {
        sample(t_k, in);
        return true;
    }, message);
}

void JointController::sample(double t, const ControllerInputs& in) {
    double omega_ref = 0.0;
    const double theta_ref = reference(t, &omega_ref);
    command(in, theta_ref, omega_ref);
    out_.tau_ext = disturbance(t);
}

double JointController::command(const ControllerInputs& in, double theta_ref, double omega_ref) {
    if (has_previous_) {
        const double alpha = 1.0 - std::exp(-p_.speed_filter * p_.Ts);
        omega_hat_ += alpha * ((in.theta_m - previous_theta_m_) / p_.Ts - omega_hat_);
        tau_rate_ += alpha * ((in.tau_fb - previous_tau_fb_) / p_.Ts - tau_rate_);
    }
    previous_theta_m_ = in.theta_m;
    previous_tau_fb_ = in.tau_fb;
    has_previous_ = true;

    const double NKt = p_.N * p_.Kt;
    const double tau_d = NKt * (p_.kp * (p_.N * theta_ref - in.theta_m) + p_.kd * (p_.N * omega_ref - omega_hat_)) +
                         p_.mgl * std::sin(theta_ref);
    double tau_cmd = tau_d;
    if (p_.jtf == 1.0) {
        const double e = tau_d - in.tau_fb;
        const double limit = NKt * p_.i_max;
        const double without_integral = tau_cmd + p_.k_tau * e - p_.d_tau * tau_rate_;
        // Conditional integration (anti-windup): not while the current limit
        // holds the command and integrating would push it further out.
        const double candidate = std::clamp(integral_ + p_.ki_tau * p_.Ts * e, -limit, limit);
        const double unsaturated = without_integral + candidate;
        if (std::fabs(unsaturated) <= limit || std::fabs(unsaturated) < std::fabs(without_integral + integral_))
            integral_ = candidate;
        tau_cmd = without_integral + integral_;
    }
    out_.i_m = std::clamp(tau_cmd / NKt, -p_.i_max, p_.i_max);
    out_.tau_d = tau_d;
    out_.theta_ref = theta_ref;
    out_.e_link = theta_ref - in.theta_l;
    return out_.i_m;
}

}  // namespace hdjoint
