#pragma once
// The joint itself: motor (eq. 2), harmonic drive compliance (eq. 3-8 with
// the wave generator carrying tau_f/N), link with inertia, damping, gravity
// and an external torque, and quantised encoders.
//
// Integrator: the linearly implicit Rosenbrock method ROS2 (Verwer et al.
// 1999; L-stable, second order for any Jacobian) on fixed substeps of at most
// `max_step`. Why: the torsional resonance (tens of Hz) is resolved with
// hundreds of substeps per period, and friction laws with a steep slope at
// zero speed (smoothed Coulomb, the LuGre bristles) are stiff; an explicit
// method goes unstable there, ROS2 damps them like the physics does. It
// needs one LU a substep and no Newton iterations, so its cost is fixed and
// state save/restore exact.
//
// Beyond the paper (each off by default): the friction and cogging of
// friction.h, backlash, and three states of their own -- Dahl hysteresis
// (hys_H), Bouc-Wen hysteresis (bw_A) in the transmission and LuGre motor
// friction (lugre_sigma0). Only when one of these is on does the plant
// integrate its 7 states (a 7x7 LU); otherwise the 4 mechanical ones, as the
// paper's model.
#include <cmath>
#include <string>
#include <vector>

#include "friction.h"
#include "linear_algebra.h"
#include "parameters.h"
#include "plant_signals.def"
#include "signal_table.h"
#include "state_fields.h"

namespace hdjoint {

struct PlantInputs {
    HDJ_PLANT_SIGNALS(HDJ_MEMBER, HDJ_SKIP, HDJ_SKIP)
};

struct PlantOutputs {
    HDJ_PLANT_SIGNALS(HDJ_SKIP, HDJ_MEMBER, HDJ_MEMBER)
};

// The rows of plant_signals.def.
const SignalTable<PlantInputs, PlantOutputs>& plant_signals();

// Torques inside the joint that no output shows (for analysis and diagnosis).
struct PlantInternals {
    double tau_friction = 0.0;       // motor-side friction, viscous included, N.m
    double tau_cogging = 0.0;        // cogging torque on the motor, N.m
    double tau_link_friction = 0.0;  // link-side Coulomb friction, N.m
    double friction_scale = 1.0;     // drift and warm-up of the Coulomb+Stribeck friction
    double z_dahl = 0.0;             // Dahl hysteresis torque in the transmission, N.m
    double z_bouc_wen = 0.0;         // Bouc-Wen hysteresis torque in the transmission, N.m
    double z_lugre = 0.0;            // LuGre bristle deflection, rad
    double elastic_torsion = 0.0;    // theta_m/N - theta_l - theta_err, rad
};

// Mechanical state: [theta_m, omega_m, theta_l, omega_l].
using PlantState = Vector<4>;
namespace plant_state {  // its own namespace: the joint-state filter names its states too
enum Index : int { kThetaM = 0, kOmegaM = 1, kThetaL = 2, kOmegaL = 3 };
}  // namespace plant_state
// With the states of the beyond-paper effects: [..., z_dahl, z_bouc_wen, z_lugre].
constexpr int kPlantStates = 7;
using PlantFullState = Vector<kPlantStates>;
using PlantJacobian = Matrix<kPlantStates>;

class JointPlant {
public:
    explicit JointPlant(const Parameters& p);

    // Place the joint at rest in static equilibrium at theta_l0 under
    // gravity and `tau_ext`. False (with a message) when no torque holds it.
    bool initialize(double tau_ext, std::string* message = nullptr);

    // At most this many substeps of max_step per advance (10^5: 10 s at the
    // default max_step, well under a second of computing); a longer advance
    // is refused whole, with a message.
    static constexpr double kMaxSubstepsPerAdvance = 1e5;

    // Advance by h seconds with inputs held. False (with a message) when the
    // state leaves the model's domain (singular torsion, non-finite state)
    // or h needs more than kMaxSubstepsPerAdvance substeps.
    bool advance(double h, const PlantInputs& in, std::string* message = nullptr);

    PlantOutputs outputs() const;
    const PlantState& state() const { return x_; }
    PlantFullState full_state() const;
    double time() const { return t_; }  // since initialize(); drives the friction drift and warm-up
    const Parameters& parameters() const { return p_; }

    // Transmitted torque for a state (with the plant's present hysteresis
    // torque); false outside the model's domain.
    bool joint_torque(const PlantState& x, double* tau) const;

    PlantInternals internals() const;

    // The state as named fields (parameters excluded; see state_fields.h).
    template <class Archive>
    bool fields(Archive& a) {
        long version = kLayoutVersion;  // a counter: checked in every reading
        return a("plant_state_version", version, kLayoutVersion, kLayoutVersion) && a("theta_m", x_(plant_state::kThetaM)) &&
               a("omega_m", x_(plant_state::kOmegaM)) && a("theta_l", x_(plant_state::kThetaL)) && a("omega_l", x_(plant_state::kOmegaL)) &&
               a("time", t_, 0.0, kUnbounded) && a("z_dahl", z_(0)) && a("z_bouc_wen", z_(1)) && a("z_lugre", z_(2));
    }
    // The same as a flat vector ([version, theta_m, omega_m, theta_l, omega_l, time, z_dahl, z_bouc_wen, z_lugre]).
    std::vector<double> save_state() const { return save_fields(*this); }
    bool load_state(const std::vector<double>& data) { return load_fields(*this, data); }

    // Model Exchange: a solver moves the state and the clock itself and asks
    // for derivative(); these place the plant where it asks (no checks: the
    // derivative reports a state outside the model's domain).
    void set_full_state(const PlantFullState& x) {
        x_ = x.head<4>();
        z_ = x.tail<3>();
    }
    void set_time(double t) { t_ = t; }
    // Whether a state is one the joint can be in: finite, its elastic torsion
    // inside the atan law's asymptote (a torque explains it). Co-Simulation's
    // advance fails outside it (singular torsion); Model Exchange refuses such
    // a state. `elastic`: the state's elastic torsion, rad.
    bool physical(const PlantFullState& x, double* elastic = nullptr) const;
    // The state events (plant_signals.def, HDJ_PLANT_EVENT_INDICATORS): the
    // backlash's two contact edges, each a constant 1 without backlash.
    static constexpr int kEventIndicators = 2;
    Vector<kEventIndicators> event_indicators() const;

    // State derivative at time t (since initialize) and its Jacobian by the
    // state (analytic; public so tests can check it against differences).
    // False beyond the torsion asymptote (no torque) or where it is not
    // finite: Model Exchange refuses such a state (physical()).
    bool derivative(const PlantFullState& x, double t, const PlantInputs& in, PlantFullState* dx,
                    PlantJacobian* J) const;

private:
    // The model on S = 4 (mechanical) or S = 7 (all) states.
    template <int S>
    bool model(const Vector<S>& x, double t, const PlantInputs& in, Vector<S>* dx, Matrix<S>* J) const;
    template <int S>
    bool ros2_step(double h, const PlantInputs& in, std::string* message);
    bool torque(const PlantState& x, const Vector<3>& z, double* tau) const;
    bool within_bounds(const Vector<3>& z, double h) const;
    bool extra_states() const { return p_.hys_H > 0.0 || p_.bw_A > 0.0 || p_.lugre_sigma0 > 0.0; }
    bool substep(double h, const PlantInputs& in, int depth, std::string* message);
    static constexpr int kMaxHalvings = 10;
    static constexpr long kLayoutVersion = 3;

    Parameters p_;
    PlantState x_ = PlantState::Zero();
    Vector<3> z_ = Vector<3>::Zero();  // z_dahl, z_bouc_wen, z_lugre
    double t_ = 0.0;
};

// The link's equation of motion, Jl*alpha_l = link_net_torque(...): the
// transmitted torque less damping, gravity, the external torque and link friction.
inline double link_net_torque(double tau, double theta_l, double omega_l, double tau_ext, const Parameters& p) {
    double load = tau - p.Bl * omega_l - p.mgl * std::sin(theta_l) - tau_ext;
    if (p.Fl != 0.0) load -= link_friction(omega_l, p);
    return load;
}
// The same solved for the transmitted torque with no external torque: what
// the link's own motion needs (the diagnosis's link channel).
inline double link_torque_needed(double theta_l, double omega_l, double alpha_l, const Parameters& p) {
    return p.Jl * alpha_l - link_net_torque(0.0, theta_l, omega_l, 0.0, p);
}

// Encoder reading: whole counts (floor), 0 counts means no quantisation.
double quantise(double angle, double counts_per_revolution);

}  // namespace hdjoint
