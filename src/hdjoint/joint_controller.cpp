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

JointController::JointController(const ControllerParameters& p, double start_time) : p_(p), start_time_(start_time) {
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

void JointController::advance(double t, double h, const ControllerInputs& in) {
    const double tolerance = 1e-6 * p_.Ts;
    // Samples fall on start + k*Ts (computed from k, so no round-off builds up).
    while (start_time_ + static_cast<double>(next_sample_) * p_.Ts < t + h - tolerance) {
        sample(start_time_ + static_cast<double>(next_sample_) * p_.Ts, in);
        ++next_sample_;
    }
}

void JointController::sample(double t, const ControllerInputs& in) {
    if (has_previous_) {
        const double alpha = 1.0 - std::exp(-p_.speed_filter * p_.Ts);
        omega_hat_ += alpha * ((in.theta_m - previous_theta_m_) / p_.Ts - omega_hat_);
        tau_rate_ += alpha * ((in.tau_fb - previous_tau_fb_) / p_.Ts - tau_rate_);
    }
    previous_theta_m_ = in.theta_m;
    previous_tau_fb_ = in.tau_fb;
    has_previous_ = true;

    double omega_ref = 0.0;
    const double theta_ref = reference(t, &omega_ref);
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
    out_.tau_ext = disturbance(t);
}

std::vector<double> JointController::save_state() const {
    return {start_time_, static_cast<double>(next_sample_), has_previous_ ? 1.0 : 0.0, previous_theta_m_,
            omega_hat_, out_.i_m, out_.tau_ext, out_.theta_ref, out_.tau_d, out_.e_link,
            previous_tau_fb_, tau_rate_, integral_};
}

bool JointController::load_state(const std::vector<double>& s) {
    if (s.size() != 13) return false;
    start_time_ = s[0];
    next_sample_ = static_cast<long>(s[1]);
    has_previous_ = s[2] != 0.0;
    previous_theta_m_ = s[3];
    omega_hat_ = s[4];
    out_ = {s[5], s[6], s[7], s[8], s[9]};
    previous_tau_fb_ = s[10];
    tau_rate_ = s[11];
    integral_ = s[12];
    return true;
}

}  // namespace hdjoint
