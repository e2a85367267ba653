#pragma once
// The joint's controller, for system simulation (JointController.fmu): a
// link position PD on the motor encoder with gravity feed-forward, and an
// optional inner joint-torque loop (joint torque feedback, JTF) on a torque
// signal -- the UKF estimate or a torque sensor. It also generates the
// reference trajectory and the external load disturbance, so a system needs
// no other source. Sampled at the fixed period Ts.
//
// The law, at each sample t_k = t0 + k*Ts:
//   theta_ref = ref_offset + ref_amplitude*(1 - cos(2*pi*ref_frequency*t_k))
//   omega_hat: first-order filtered difference of theta_m
//   tau_d = N*Kt*(kp*(N*theta_ref - theta_m) + kd*(N*omega_ref - omega_hat)) + mgl*sin(theta_ref)
//   i_m = tau_d/(N*Kt)                                    (jtf = 0)
//   i_m = (tau_d + k_tau*e + ki_tau*integral(e) - d_tau*d(tau_fb)/dt)/(N*Kt),
//         e = tau_d - tau_fb                              (jtf = 1)
// saturated to +-i_max. tau_d is the joint torque the position loop asks for.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "controller_signals.def"
#include "sample_clock.h"
#include "signal_table.h"

namespace hdjoint {

struct ControllerParameters {
#define HDJ_CONTROLLER_PARAMETER(name, unit, def, lo, hi, description) double name = def;
#include "controller_table.def"
#undef HDJ_CONTROLLER_PARAMETER
};

struct ControllerParameterInfo {
    const char* name;
    const char* unit;
    double default_value;
    double min;
    double max;
    const char* description;
    double ControllerParameters::*member;
};

// The table in declaration order; the index is the FMI value reference.
const ControllerParameterInfo* controller_parameter_table();
std::size_t controller_parameter_count();

// First problem with a parameter set, or nothing.
std::optional<std::string> validate(const ControllerParameters& p);

struct ControllerInputs {
    HDJ_CONTROLLER_SIGNALS(HDJ_MEMBER, HDJ_SKIP, HDJ_SKIP)
};

struct ControllerOutputs {
    HDJ_CONTROLLER_SIGNALS(HDJ_SKIP, HDJ_MEMBER, HDJ_MEMBER)
};

// The rows of controller_signals.def.
const SignalTable<ControllerInputs, ControllerOutputs>& controller_signals();

class JointController {
public:
    explicit JointController(const ControllerParameters& p, double start_time = 0.0);

    // Outputs before the first sample: the reference and load at the start,
    // no current yet.
    ControllerOutputs outputs() const { return out_; }

    // Processes the samples in [t, t + h) with inputs held at `in`. False
    // (with a message, nothing run) beyond SampleClock::kMaxSamplesPerStep samples.
    bool advance(double t, double h, const ControllerInputs& in, std::string* message = nullptr);

    // The control law alone at one sample, on a reference from outside
    // (theta_ref, omega_ref): updates the speed and torque-rate filters and
    // returns the saturated current command. advance() calls it with the
    // built-in reference; the built-in experiments (hdjoint.experiments) with theirs.
    double command(const ControllerInputs& in, double theta_ref, double omega_ref);

    // The reference and the load at time t (pure functions of time).
    double reference(double t, double* omega_ref) const;
    double disturbance(double t) const;

    // The state as named fields (parameters excluded; see state_fields.h),
    // and the same as a flat vector.
    std::vector<double> save_state() const { return save_fields(*this); }
    bool load_state(const std::vector<double>& data) { return load_fields(*this, data); }
    template <class Archive>
    bool fields(Archive& a) {
        return clock_.fields(a) && a("has_previous", has_previous_) && a("previous_theta_m", previous_theta_m_) &&
               a("omega_hat", omega_hat_) && a("previous_tau_fb", previous_tau_fb_) && a("tau_rate", tau_rate_) &&
               a("integral", integral_) && output_fields(a, controller_signals(), out_);
    }

private:
    void sample(double t, const ControllerInputs& in);

    ControllerParameters p_;
    SampleClock clock_;
    bool has_previous_ = false;
    double previous_theta_m_ = 0.0;
    double omega_hat_ = 0.0;
    double previous_tau_fb_ = 0.0;
    double tau_rate_ = 0.0;     // filtered d(tau_fb)/dt, N.m/s
    double integral_ = 0.0;     // ki_tau * integral of (tau_d - tau_fb), N.m
    ControllerOutputs out_;
};

}  // namespace hdjoint
