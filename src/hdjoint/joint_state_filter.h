#pragma once
// The joint-state filter (beyond the paper): the two-mass joint as a Kalman
// filter on the raw encoder angles, driven by the motor current, and an
// offline Rauch-Tung-Striebel smoother over it.
//
// State x = [theta_l, omega_l, delta, nu, w, r, g, e, s] (link-side units):
//   theta_l, omega_l  link angle and speed,
//   delta = theta_m/N - theta_l   total torsion (its own state: theta_m/N and
//                                 theta_l are almost perfectly correlated),
//   nu = d(delta)/dt              torsion rate (omega_m = N*(omega_l + nu)),
//   w                             link load: whatever else acts on the link
//                                 (external torque, Jl/Bl/mgl errors), a random walk
//                                 plus its rate r (an integrated random walk: loads
//                                 that ramp, such as contacts, are followed without lag).
//   g                             the link inertia's relative error: the link's
//                                 inertia is Jl*(1 + g), g a constant the filter learns
//                                 (prior kP0InertiaError); a Jl 5 % off otherwise makes
//                                 the load w follow 5 % of the inertial torque.
//   e                             the compliance model's error, N.m: the transmitted
//                                 torque is tau(x) + e, e a random walk (jsf_q_torque).
//                                 A stiffness or kinematic error, hysteresis: the motor
//                                 equation sees them and the encoders cannot. Without it
//                                 such an error is a conflict between the current and the
//                                 readings that the filter settles with a lag and the
//                                 smoother, from both sides, without one: tau_smooth then
//                                 follows the wrong compliance model more than tau_hat.
//   s                             the current sensor's gain error as the filter undoes
//                                 it: the motor carries (1 + s)*i_m (prior
//                                 jsf_current_gain, a datasheet's accuracy). Without it
//                                 e follows N*Kt*s*i_m, a bias of tau_hat in proportion
//                                 to the torque: no other state acts on the motor side
//                                 alone. (s, e, w) has an unobservable direction; the
//                                 priors split it. An offset state was tried and left
//                                 out: a constant motor torque is also the friction at
//                                 rest and a constant compliance error: learned, it took
//                                 them in and biased tau_hat on the independent truth
//                                 (benchmarks/filter_on_truth.py). Its stated accuracy
//                                 widens tau_std instead (unseen_variance).
//   d(w)/dt = r, d(r)/dt = noise, d(g)/dt = 0, d(e)/dt = noise, s drifts slowly
// Dynamics, with tau(x) the transmitted torque of the corrected compliance
// chain (eq. 3-8 with kinematic error, wave generator, backlash, the
// Dahl hysteresis torque z of the filter's own torsion, follow_hysteresis)
// plus the structural damping Df times the elastic torsion rate (as the joint
// has it: without it the filter's torsional mode is undamped where the
// joint's is not, and the smoother, trusting that mode from both sides,
// lost to tau_hat on the independent truth):
//   Jl*(1 + g)*d(omega_l)/dt = tau - Bl*omega_l - mgl*sin(theta_l) - w
//   N*Jm*d(omega_l + nu)/dt  = Kt*(1 + s)*i_m + cogging - tau_fm(omega_m) - Bm*omega_m - tau/N
// discretised by the linearly implicit trapezoidal rule (A-stable, keeps the
// undamped torsional resonance undamped; F = (I - h/2 J)^-1 (I + h/2 J)).
// The Coulomb law tau_fm is the mean of Fc*tanh(omega_m/omega_fc) over the
// motor speed's spread in P: omega_fc^2 becomes omega_fc^2 + (pi/2) Var(omega_m).
// Process noise: the current noise (and an unmodelled motor torque) as a
// piecewise-constant acceleration on nu, random walks on w and r; near rest,
// the friction the law misses (jsf_q_stiction: a stuck rotor's friction holds
// what the spring does not, and the current then says nothing of the torque).
// Measurements: theta_m = N*(theta_l + delta) and theta_l, read by floor
// quantisers: the reading plus q/2 is unbiased with variance q^2/12; a
// reading that repeats the last one k times over has (1 + 0.02 k) q^2/12
// (its quantisation error is the same, not a fresh one; kRepeatedReadingWeight).
// Output: tau(x) and its standard deviation from P, with the variance of the
// current sensor's offset (jsf_current_offset), which no state can see.
#include <cmath>
#include <cstddef>
#include <vector>

#include "linear_algebra.h"
#include "parameters.h"
#include "ukf.h"

namespace hdjoint {

constexpr int kJointStates = 9;
// Named indices of the state vector.
namespace joint_state {
enum Index : int {
    kThetaL = 0,
    kOmegaL = 1,
    kDelta = 2,
    kNu = 3,
    kLoad = 4,
    kLoadRate = 5,
    kInertiaError = 6,
    kTorqueError = 7,
    kCurrentScale = 8
};
}
static_assert(joint_state::kNu == joint_state::kDelta + 1, "the motor noise acts on (delta, nu) as one block");
using JointState = Vector<kJointStates>;
using JointCovariance = Matrix<kJointStates>;

// What the dynamics hold over a sample: the current, the hysteresis torque
// z and its slope dz by the elastic torsion, and the time (friction drift).
// The filter replaces z and dz by the Dahl law (hys_H) of its own torsion
// (JointStateFilter::follow_hysteresis).
struct JointInput {
    double i_m = 0.0;
    double z = 0.0;
    double t = 0.0;
    double dz = 0.0;  // N.m/rad: the hysteresis stiffens the transmission in the direction of motion
};

// The transmitted torque of a state (tau(x) + z + e) and its gradient by the
// state (by e it is 1; the hysteresis adds its slope dz to the stiffness).
struct JointTorque {
    double tau = 0.0;
    double d_theta_l = 0.0;  // d tau / d theta_l
    double d_delta = 0.0;    // d tau / d delta
    double d_omega_l = 0.0;  // d tau / d omega_l (the structural damping Df)
    double d_nu = 0.0;       // d tau / d nu
    bool valid = false;
};
JointTorque joint_state_torque(const JointState& x, const JointInput& in, const Parameters& p);

// The system model for the generic filter (kExtended: step() gives the
// next state and the transition Jacobian).
struct JointSystemModel {
    using State = JointState;
    using Control = JointInput;
    static constexpr bool kExtended = true;
    // States from kLoadRate on are constants or random walks: F's rows there are the identity's.
    static constexpr int kMovingStates = joint_state::kLoadRate;
    Parameters p;  // by value: the filter is copied (FMU state) and must not point into another
    double h = 1e-3;

    // Continuous dynamics dx/dt and its Jacobian J (false: singular torsion).
    bool derivative(const State& x, const Control& u, State* dx, JointCovariance* J) const;
    // joint_state_torque, remembering the last point: the filter's output at
    // a posterior is where the next prediction starts (same state, same input).
    JointTorque torque(const State& x, const Control& u) const;

private:
    mutable bool cached_ = false;
    mutable State cached_x_ = State::Zero();
    mutable Control cached_u_;
    mutable JointTorque cached_torque_;

public:
    State step(const State& x, const Control& u, JointCovariance* F) const;
    State f(const State& x, const Control& u) const {
        JointCovariance F;
        return step(x, u, &F);
    }
};

// theta_m and theta_l, linear in the state. A reading taken `age` seconds
// before the sample (a jittered recording: the row came a little before the
// sample that uses it) is of the link angle then, to first order
// theta_l - age*omega_l; the torsion is taken as read (its rate swings with
// the torsional mode, which a first-order shift over a few ms would not follow).
struct JointMeasurementModel {
    static constexpr int kSize = 2;
    static constexpr bool kLinear = true;
    using Vector = hdjoint::Vector<2>;
    using Covariance = Matrix<2>;
    double N = 100.0;
    double age = 0.0;  // s

    Eigen::Matrix<double, 2, kJointStates> jacobian() const {
        using namespace joint_state;
        Eigen::Matrix<double, 2, kJointStates> H = Eigen::Matrix<double, 2, kJointStates>::Zero();
        H(0, kThetaL) = N;
        H(0, kDelta) = N;
        H(1, kThetaL) = 1.0;
        if (age != 0.0) {
            H(0, kOmegaL) = -age * N;
            H(1, kOmegaL) = -age;
        }
        return H;
    }
    Vector h(const JointState& x) const {
        using namespace joint_state;
        const double theta_l = x(kThetaL) - age * x(kOmegaL);
        return Vector(N * (theta_l + x(kDelta)), theta_l);
    }
};

// One sample of the filter, kept for the smoother.
struct JointFilterRecord {
    JointState x_prior = JointState::Zero();
    JointCovariance P_prior = JointCovariance::Zero();
    JointCovariance F = JointCovariance::Identity();  // from the previous sample to this one
    JointState x = JointState::Zero();
    JointCovariance P = JointCovariance::Zero();
    JointInput input;  // this sample's current, hysteresis torque and time
    bool predicted = false;  // false for the first sample (no prior)
};

struct JointFilterOutput {
    double tau = 0.0;
    double tau_std = 0.0;
    double load = 0.0;  // w, N.m
    double nis = 0.0;   // of the update, or of the rejected innovation
};

// How much a repeated encoder reading's quantisation variance grows per
// repeat (reading_covariance). Measured on the benchmark's sweeps with dwells
// (docs/estimators.md): without it the smoother's +-2 sigma covered 73.6 % of
// the true torque there (the white q^2/12 model averages a constant error
// away); 0.01 gives 94.4 %, 0.02 95.4 % (tau_hat 96.7 %), 0.05 96.2 % (tau_hat
// 97.1 %), 0.3 97.5 % (tau_hat 98.0 %); the RMS error is within 5 % across them.
constexpr double kRepeatedReadingWeight = 0.02;

// How many encoder counts of the spring's torque an imbalance at rest must
// exceed before jsf_q_stiction takes it as friction: within them the readings
// cannot tell it from the torsion's place inside a count (the joint benchmark's
// dwells, where the law holds at rest, lose tau_hat's lead there below 1.5).
constexpr double kRestFrictionCounts = 1.5;

// The prior deviation of the link inertia's relative error g (10 %: a link
// model from CAD or a catalogue), and its random walk per sample (it may
// drift slowly: a payload changes it).
constexpr double kP0InertiaError = 0.1;
constexpr double kQInertiaError = 1e-5;

// How long the current sensor's gain takes to drift by its prior's deviation
// (s): a Hall sensor follows its temperature over minutes.
constexpr double kCurrentDriftTime = 600.0;

// NIS above which a sample is an outlier. On the benchmark's valid samples
// (payload steps, contacts, hysteresis, coarse encoders) the gate rejects
// none (docs/estimators.md); a 1e6 A current or a glitched reading gives NIS
// of 1e9 and more.
constexpr double kOutlierGate = 1.0e4;
// ... and whose innovation is larger than this link-side angle, rad: in
// torsion 1e-2 rad is some 100 N.m at the default stiffness, beyond what the
// transmission carries; a model error of the filter stays far below it.
constexpr double kOutlierAngle = 1.0e-2;

class JointStateFilter {
public:
    JointStateFilter() = default;
    explicit JointStateFilter(const Parameters& p);

    // One sample: encoder readings (already matched with the current by the
    // compliance model's delay line) and the input held from this sample on.
    // The first call initialises at rest in static balance.
    //
    // Outliers: a sample whose innovation fails the gate (NIS > kOutlierGate
    // and an innovation above kOutlierAngle)
    // is retried with the last input that passed it (the current held over
    // the last sample may be the outlier); if it fails again, or the readings
    // are not finite, the update is skipped and the filter only predicts, so
    // tau_std grows. Either way the status is SampleRejected and the next
    // valid sample is used as usual. Readings that fail twice in a row are
    // taken without the gate (a jump that persists is real: no lock-out).
    // `age`: how long before this sample the readings were taken (s, 0 on a
    // regular recording; see JointMeasurementModel).
    FilterStatus step(double theta_m, double theta_l, const JointInput& in, double age = 0.0);

    // A sample without a reading (a gap: the inputs were held over it, so the
    // encoders were not read at this sample's time): the filter only
    // predicts, with the input held since the last sample, and P grows, so
    // does tau_std. The current is not known over the gap either: the k-th
    // sample without a reading adds k times the last change of the current
    // between two readings (|di|) to the current's noise, a ramp the held
    // value misses. Nothing happens before the first sample.
    void predict_without_reading(const JointInput& in);

    const JointFilterOutput& output() const { return out_; }
    const JointFilterRecord& record() const { return record_; }
    const JointState& state() const { return kalman_.state(); }
    const JointCovariance& covariance() const { return kalman_.covariance(); }
    bool started() const { return started_; }

    // Flat state: 1 + 9 + 81 + 4 + 4 + 4 + 2 + 2 + 4 + 3 values.
    static constexpr std::size_t kSavedSize = 114;

    // The variance of a torque at a state of covariance P (first order).
    static double torque_variance(const JointTorque& T, const JointCovariance& P);
    // What no state sees: the current sensor's offset, N*Kt*jsf_current_offset
    // on the transmitted torque (e takes it in), as a variance.
    static double unseen_variance(const Parameters& p);
    void save(std::vector<double>* out) const;
    bool load(const std::vector<double>& in, std::size_t* cursor);

private:
    // Torque, its std and the load from the current state and inputs; false
    // (the last torque kept) when no torque explains the state.
    bool publish_state();

    Parameters p_;
    JointSystemModel system_;
    JointMeasurementModel measurement_;
    JointCovariance Q_ = JointCovariance::Zero();
    // G G^T of a motor torque held over a sample, on (delta, nu): the shape of
    // the friction-at-rest noise (jsf_q_stiction) process_noise adds.
    Matrix<2> motor_noise_shape_ = Matrix<2>::Zero();
    Matrix<2> R_ = Matrix<2>::Identity();
    double offset_m_ = 0.0, offset_l_ = 0.0;  // q/2 of the floor quantisers
    // The generic filter in its extended mode (kExtended: analytic Jacobian,
    // no sigma points are drawn).
    UnscentedKalmanFilter<kJointStates> kalman_;
    JointInput previous_;  // the input held since the last sample
    JointInput accepted_;  // the last held input whose prediction passed the gate
    // Running mean of NIS / 2 (1 when the innovations are as expected): the
    // load states' process noise is scaled by max(1, it) (jsf_load_adapt_time).
    double load_noise_scale_ = 1.0;
    bool readings_rejected_ = false;  // the last sample's readings failed the gate
    double current_change_ = 0.0;  // |di| between the last two samples with readings, A
    double samples_held_ = 0.0;    // samples predicted without a reading since the last reading
    // The last readings and how many samples before them read the same (a
    // repeated reading carries the same quantisation error: reading_covariance).
    double last_m_ = 0.0, last_l_ = 0.0;
    double repeats_m_ = 0.0, repeats_l_ = 0.0;
    double quantisation_m_ = 0.0, quantisation_l_ = 0.0;  // q^2/12 of each encoder, rad^2
    Matrix<2> reading_covariance(double theta_m, double theta_l);
    // The readings' variance from when they were taken (jsf_r_time), at the predicted state.
    Matrix<2> timing_covariance() const;
    double adapt_weight_ = 0.0;  // Ts / jsf_load_adapt_time (0: off)
    JointCovariance process_noise() const;
    // The prediction's Coulomb law (system_.p.omega_fc) averaged over the
    // motor speed's uncertainty in P: a calibrated omega_fc near 0 (a sign
    // law) otherwise has a slope at rest no linearisation can follow.
    void average_friction_over_speed();
    // The Dahl hysteresis torque (hys_H, hys_sigma) of the posterior's elastic
    // torsion and its slope, held in previous_ over the next sample. The
    // compliance model's z follows the readings, whose count can be wider than
    // the whole loop: there the filter's dynamics would miss the stiffening.
    void follow_hysteresis(bool first);
    double hysteresis_ = 0.0;  // z, N.m
    double torsion_ = 0.0;     // the elastic torsion it was last updated at, rad
    double direction_ = 0.0;   // the sign of the torsion's last move (0 before any)
    // The NIS gate for readings z at the predicted state: kOutlierGate, or
    // none when the innovation is below kOutlierAngle.
    double gate(const Vector<2>& z) const;
    // The last sample: the smoother's record, and the (x, P) a rejected
    // sample starts over from.
    JointFilterRecord record_;
    void record_prior();  // the prediction's x_prior and P_prior, for the smoother
    JointFilterOutput out_;
    bool started_ = false;
};

// A record as flat doubles (x_prior, P_prior, F, x, P column-major, the
// input's i_m, z, t, dz, predicted as 0/1), for a smoother whose records wait
// on disk between its forward and backward pass.
constexpr std::size_t kRecordValues = 2 * kJointStates + 3 * kJointStates * kJointStates + 4 + 1;
void flatten_record(const JointFilterRecord& r, double* out);
JointFilterRecord unflatten_record(const double* in);

// The RTS smoother's backward pass one sample at a time, the newest first. It
// carries the smoothed state and the later sample's record from one sample
// to the one before, so the records can come in reverse blocks.
class RtsBackward {
public:
    explicit RtsBackward(const Parameters& p) : p_(p) {}
    struct Torque {
        double tau, tau_std;
    };
    // The smoothed torque at `r`, the sample just before the one last given.
    // Where no torque explains the smoothed state (its torsion past eq. (8)'s
    // pole: a large correction on a poor model), the filter's own at `r` is
    // given with its deviation, and failing that the later sample's (NaN only
    // while no torque has been explained yet).
    Torque step(const JointFilterRecord& r);

private:
    Parameters p_;
    bool has_next_ = false;
    JointFilterRecord next_;                        // the later sample
    JointState xs_ = JointState::Zero();            // and its smoothed state
    JointCovariance Ps_ = JointCovariance::Zero();  // and covariance
    Torque given_{std::nan(""), std::nan("")};      // the torque given for the later sample
};

// The RTS smoother over filter records (one per sample, in order): the
// smoothed torque of each sample and its standard deviation.
struct SmoothedTorque {
    std::vector<double> tau, tau_std;
};
SmoothedTorque smooth_joint_states(const std::vector<JointFilterRecord>& records, const Parameters& p);

}  // namespace hdjoint
