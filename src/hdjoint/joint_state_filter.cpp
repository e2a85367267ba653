#include "joint_state_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "friction.h"
#include "hysteresis.h"
#include "transmission.h"

namespace hdjoint {

namespace {
constexpr double kTwoPi = 6.283185307179586;
// Variance floor of an encoder reading with neither quantisation nor noise, rad^2.
constexpr double kMinReadingVariance = 1e-24;
// Initial spread of the states the first reading does not fix (link speed,
// torsion rate in rad/s; angles in rad); the first update then sets them.
constexpr double kP0Angle = 1e-2, kP0Torsion = 1e-3, kP0Speed = 0.1;
constexpr double kMinTorqueErrorStd = 1e-6;  // N.m
constexpr double kMinCurrentGainStd = 1e-9;  // a sensor taken as exact

double resolution(double counts) { return counts > 0.0 ? kTwoPi / counts : 0.0; }

// The current the motor carries, the sensor's gain error undone.
double corrected_current(const JointState& x, double i_m) { return (1.0 + x(joint_state::kCurrentScale)) * i_m; }
}  // namespace

JointTorque joint_state_torque(const JointState& x, const JointInput& in, const Parameters& p) {
    JointTorque t;
    const double theta_l = x(joint_state::kThetaL), theta_m = p.N * (theta_l + x(joint_state::kDelta));
    const ComplianceEstimate c = compliance_estimate(in.i_m, theta_m, theta_l, p);
    if (!c.valid) return t;
    // d tau / d y, y = delta - theta_err: the flexspline's stiffness (none
    // inside the backlash), softened by the wave generator when it is loaded
    // by the transmitted torque.
    double k = in_backlash(c.dtheta_f, p) ? 0.0 : 1.0 / flexspline_compliance(c.tau, p);
    if (p.wg_load > 0.0 && k > 0.0) {
        const double tau_w = (1.0 - p.wg_load) * p.Kt * in.i_m + p.wg_load * c.tau / p.N;
        k /= 1.0 + k * p.wg_load / p.N * wave_generator_compliance(tau_w, p);
    }
    k += in.dz;
    double e_m = 0.0, e_l = 0.0;
    kinematic_error_gradient(theta_m, theta_l, p, &e_m, &e_l);
    t.tau = c.tau + in.z + x(joint_state::kTorqueError);
    t.d_delta = k * (1.0 - p.N * e_m);
    t.d_theta_l = k * (-p.N * e_m - e_l);
    if (p.Df != 0.0) {  // the structural damping of the elastic torsion rate, as the joint has it
        const double omega_l = x(joint_state::kOmegaL), omega_m = p.N * (omega_l + x(joint_state::kNu));
        double d[4];  // by theta_m, omega_m, theta_l, omega_l
        elastic_torsion_rate_gradient(theta_m, omega_m, theta_l, omega_l, p, e_m, e_l, d);
        t.tau += p.Df * (d[1] * omega_m + d[3] * omega_l);  // the rate is linear in the speeds
        t.d_delta += p.Df * p.N * d[0];
        t.d_theta_l += p.Df * (p.N * d[0] + d[2]);
        t.d_nu = p.Df * p.N * d[1];
        t.d_omega_l = p.Df * (p.N * d[1] + d[3]);
    }
    t.valid = std::isfinite(t.tau);
    return t;
}

JointTorque JointSystemModel::torque(const State& x, const Control& u) const {
    if (!(cached_ && x == cached_x_ && u.i_m == cached_u_.i_m && u.z == cached_u_.z && u.t == cached_u_.t &&
          u.dz == cached_u_.dz)) {
        cached_torque_ = joint_state_torque(x, u, p);
        cached_x_ = x;
        cached_u_ = u;
        cached_ = true;
    }
    return cached_torque_;
}

bool JointSystemModel::derivative(const State& x, const Control& u, State* dx, JointCovariance* J) const {
    using namespace joint_state;
    const Parameters& q = p;
    const JointTorque T = torque(x, u);
    if (!T.valid) return false;
    const double theta_l = x(kThetaL), omega_l = x(kOmegaL), nu = x(kNu), w = x(kLoad);
    const double theta_m = q.N * (theta_l + x(kDelta)), omega_m = q.N * (omega_l + nu);
    const double scale = friction_drift_scale(u.t, q);
    const double NJm = q.N * q.Jm;
    const double inertia = q.Jl * (1.0 + x(kInertiaError));
    if (!(inertia > 0.0)) return false;
    const double a_l = (T.tau - q.Bl * omega_l - q.mgl * std::sin(theta_l) - w) / inertia;
    const double a_m =
        (motor_torque(corrected_current(x, u.i_m), theta_m, u.t, q) - motor_friction(omega_m, q, scale) - T.tau / q.N) /
        NJm;
    (*dx)(kThetaL) = omega_l;
    (*dx)(kOmegaL) = a_l;
    (*dx)(kDelta) = nu;
    (*dx)(kNu) = a_m - a_l;
    (*dx)(kLoad) = x(kLoadRate);
    (*dx)(kLoadRate) = 0.0;
    (*dx)(kInertiaError) = 0.0;
    (*dx)(kTorqueError) = 0.0;
    (*dx)(kCurrentScale) = 0.0;

    const double cog = cogging_on(q) ? cogging_slope(theta_m, q) : 0.0;  // d/d theta_m
    const double friction = coulomb_friction_slope(omega_m, q, scale) + q.Bm;  // d/d omega_m
    J->setZero();
    (*J)(kThetaL, kOmegaL) = 1.0;
    (*J)(kOmegaL, kThetaL) = (T.d_theta_l - q.mgl * std::cos(theta_l)) / inertia;
    (*J)(kOmegaL, kOmegaL) = (T.d_omega_l - q.Bl) / inertia;
    (*J)(kOmegaL, kDelta) = T.d_delta / inertia;
    (*J)(kOmegaL, kNu) = T.d_nu / inertia;
    (*J)(kOmegaL, kLoad) = -1.0 / inertia;
    (*J)(kOmegaL, kInertiaError) = -a_l * q.Jl / inertia;
    (*J)(kOmegaL, kTorqueError) = 1.0 / inertia;
    (*J)(kDelta, kNu) = 1.0;
    const double am_theta_l = (cog * q.N - T.d_theta_l / q.N) / NJm;
    const double am_speed = -friction * q.N / NJm;  // by omega_l and by nu
    const double am_delta = (cog * q.N - T.d_delta / q.N) / NJm;
    (*J)(kNu, kThetaL) = am_theta_l - (*J)(kOmegaL, kThetaL);
    (*J)(kNu, kOmegaL) = am_speed - T.d_omega_l / (q.N * NJm) - (*J)(kOmegaL, kOmegaL);
    (*J)(kNu, kDelta) = am_delta - (*J)(kOmegaL, kDelta);
    (*J)(kNu, kNu) = am_speed - T.d_nu / (q.N * NJm) - (*J)(kOmegaL, kNu);
    (*J)(kNu, kLoad) = -(*J)(kOmegaL, kLoad);
    (*J)(kNu, kInertiaError) = -(*J)(kOmegaL, kInertiaError);
    (*J)(kNu, kTorqueError) = -1.0 / (q.N * NJm) - (*J)(kOmegaL, kTorqueError);
    (*J)(kNu, kCurrentScale) = q.Kt * torque_constant_scale(u.t, q) * u.i_m / NJm;
    (*J)(kLoad, kLoadRate) = 1.0;
    return dx->allFinite() && J->allFinite();
}

JointState JointSystemModel::step(const State& x, const Control& u, JointCovariance* F) const {
    State dx;
    JointCovariance J;
    if (!derivative(x, u, &dx, &J)) {
        // No torque explains the state's torsion: hold it, the update corrects it.
        F->setIdentity();
        return x;
    }
    // M = I - c*J, c = h/2. J's rows kThetaL, kDelta, kLoad are the
    // kinematic identities (d theta_l = omega_l, d delta = nu, d w = r) and
    // rows kLoadRate, kInertiaError, kTorqueError and the current's are zero, so M z = y reduces to a 2x2 system in
    // (z_omega_l, z_nu): solved in closed form (the same numbers as a general
    // LU up to round-off, at a fraction of its cost).
    using namespace joint_state;
    const double c = 0.5 * h;
    const double a11 = 1.0 - c * c * J(kOmegaL, kThetaL) - c * J(kOmegaL, kOmegaL);
    const double a13 = -c * c * J(kOmegaL, kDelta) - c * J(kOmegaL, kNu);
    const double a31 = -c * c * J(kNu, kThetaL) - c * J(kNu, kOmegaL);
    const double a33 = 1.0 - c * c * J(kNu, kDelta) - c * J(kNu, kNu);
    const double inv_det = 1.0 / (a11 * a33 - a13 * a31);  // one division for the ten solves
    auto solve = [&](const State& y) {
        State z;
        z(kLoadRate) = y(kLoadRate);
        z(kInertiaError) = y(kInertiaError);
        z(kTorqueError) = y(kTorqueError);
        z(kCurrentScale) = y(kCurrentScale);
        z(kLoad) = y(kLoad) + c * z(kLoadRate);
        auto rhs = [&](int row) {
            return y(row) + c * (J(row, kThetaL) * y(kThetaL) + J(row, kDelta) * y(kDelta) + J(row, kLoad) * z(kLoad) +
                                 J(row, kLoadRate) * z(kLoadRate) + J(row, kInertiaError) * z(kInertiaError) +
                                 J(row, kTorqueError) * z(kTorqueError) +
                                 J(row, kCurrentScale) * z(kCurrentScale));
        };
        const double r1 = rhs(kOmegaL), r3 = rhs(kNu);
        z(kOmegaL) = (a33 * r1 - a13 * r3) * inv_det;
        z(kNu) = (a11 * r3 - a31 * r1) * inv_det;
        z(kThetaL) = y(kThetaL) + c * z(kOmegaL);
        z(kDelta) = y(kDelta) + c * z(kNu);
        return z;
    };
    // F = M^-1 (I + c J) = 2 M^-1 - I.
    for (int k = 0; k < kJointStates; ++k) {
        F->col(k) = 2.0 * solve(State::Unit(k));
        (*F)(k, k) -= 1.0;
    }
    return x + solve(State(h * dx));
}

JointStateFilter::JointStateFilter(const Parameters& p) : p_(p) {
    using namespace joint_state;
    system_.p = p;
    system_.h = p.Ts;
    measurement_.N = p.N;
    // The current noise and the unmodelled motor torque, as a motor-side
    // torque held over the sample: an acceleration on nu.
    const double torque_std = std::hypot(p.Kt * p.jsf_current_noise, p.jsf_q_motor);
    const double a = torque_std / (p.N * p.Jm);
    JointState G = JointState::Zero();
    G(kDelta) = 0.5 * p.Ts * p.Ts;
    G(kNu) = p.Ts;
    Q_ = (a * a) * (G * G.transpose());
    motor_noise_shape_ = G.segment<2>(kDelta) * G.segment<2>(kDelta).transpose();
    Q_(kLoad, kLoad) = p.jsf_q_load * p.jsf_q_load;
    Q_(kLoadRate, kLoadRate) = p.jsf_q_load_rate * p.jsf_q_load_rate;
    Q_(kInertiaError, kInertiaError) = kQInertiaError * kQInertiaError;
    Q_(kTorqueError, kTorqueError) = p.jsf_q_torque * p.jsf_q_torque;
    Q_(kCurrentScale, kCurrentScale) = p.Ts / kCurrentDriftTime * p.jsf_current_gain * p.jsf_current_gain;
    // Floor quantisers: reading + q/2 is unbiased, variance q^2/12.
    const double qm = resolution(p.motor_counts), ql = resolution(p.link_counts);
    offset_m_ = 0.5 * qm;
    offset_l_ = 0.5 * ql;
    R_.setZero();
    R_(0, 0) = std::max(p.jsf_r_theta_m * p.jsf_r_theta_m + qm * qm / 12.0, kMinReadingVariance);
    R_(1, 1) = std::max(p.jsf_r_theta_l * p.jsf_r_theta_l + ql * ql / 12.0, kMinReadingVariance);
    quantisation_m_ = qm * qm / 12.0;
    quantisation_l_ = ql * ql / 12.0;
    JointState sd0;
    sd0(kThetaL) = kP0Angle;
    sd0(kOmegaL) = kP0Speed;
    sd0(kDelta) = kP0Torsion;
    sd0(kNu) = kP0Speed;
    sd0(kLoad) = p.jsf_p0_load;
    sd0(kLoadRate) = p.jsf_p0_load;  // per second
    sd0(kInertiaError) = kP0InertiaError;
    // What the walk spreads in a second (floored: a zero row would leave the
    // smoother's predicted covariance singular).
    sd0(kTorqueError) = std::max(p.jsf_q_torque / std::sqrt(p.Ts), kMinTorqueErrorStd);
    sd0(kCurrentScale) = std::max(p.jsf_current_gain, kMinCurrentGainStd);
    const JointCovariance P0 = sd0.cwiseAbs2().asDiagonal();
    adapt_weight_ = p.jsf_load_adapt_time > 0.0 ? std::min(1.0, p.Ts / p.jsf_load_adapt_time) : 0.0;
    kalman_ = UnscentedKalmanFilter<kJointStates>(merwe_weights<kJointStates>(1.0, 2.0, 0.0), JointState::Zero(), P0);
}

namespace {
bool finite(const JointInput& in) { return std::isfinite(in.i_m) && std::isfinite(in.z) && std::isfinite(in.t); }
}  // namespace

JointCovariance JointStateFilter::process_noise() const {
    using namespace joint_state;
    JointCovariance Q = Q_;
    const double s = std::max(1.0, load_noise_scale_);
    Q(kLoad, kLoad) *= s;
    Q(kLoadRate, kLoadRate) *= s;
    if (p_.jsf_q_stiction > 0.0) {
        // The friction the law misses at rest: whatever of the motor torque the
        // spring's torque does not balance (a stuck rotor's friction holds it),
        // beyond what kRestFrictionCounts of each encoder hide of the spring's
        // torque, as a motor torque held over the sample (as the current noise
        // is), fading with the speed as the law's slope does.
        const JointState& x = kalman_.state();
        const JointTorque T = system_.torque(x, previous_);
        if (T.valid) {
            const double theta_m = p_.N * (x(kThetaL) + x(kDelta)), omega_m = p_.N * (x(kOmegaL) + x(kNu));
            const Parameters& q = system_.p;  // the friction law as the prediction averages it
            const double held = motor_torque(corrected_current(x, previous_.i_m), theta_m, previous_.t, p_) -
                                motor_friction(omega_m, q, friction_drift_scale(previous_.t, p_)) -
                                (T.tau - x(kTorqueError)) / p_.N;
            // A count is twice the quantiser's offset.
            const double hidden = kRestFrictionCounts * (std::fabs(T.d_delta) * 2.0 * offset_m_ / p_.N +
                                                         std::fabs(T.d_theta_l - T.d_delta) * 2.0 * offset_l_);
            const double c = std::cosh(omega_m / q.omega_fc);
            const double a =
                p_.jsf_q_stiction * std::max(0.0, std::fabs(held) - hidden / p_.N) / (c * c * p_.N * p_.Jm);
            Q.block<2, 2>(kDelta, kDelta) += (a * a) * motor_noise_shape_;
        }
    }
    return Q;
}

void JointStateFilter::average_friction_over_speed() {
    // tanh(w/a) is erf(sqrt(pi) w / (2a)) to within 2 %, and the mean of that
    // over w ~ N(mu, s^2) is the same law of mu with a^2 + (pi/2) s^2.
    using namespace joint_state;
    const JointCovariance& P = kalman_.covariance();
    const double var_omega_m =
        p_.N * p_.N * std::max(0.0, P(kOmegaL, kOmegaL) + 2.0 * P(kOmegaL, kNu) + P(kNu, kNu));
    system_.p.omega_fc = std::sqrt(p_.omega_fc * p_.omega_fc + 0.25 * kTwoPi * var_omega_m);
}

double JointStateFilter::torque_variance(const JointTorque& T, const JointCovariance& P) {
    using namespace joint_state;
    // g^T P g over the states the torque depends on (its gradient by e is 1), P symmetric.
    const int at[5] = {kThetaL, kOmegaL, kDelta, kNu, kTorqueError};
    const double g[5] = {T.d_theta_l, T.d_omega_l, T.d_delta, T.d_nu, 1.0};
    double variance = 0.0;
    for (int i = 0; i < 5; ++i) {
        double row = 0.5 * g[i] * P(at[i], at[i]);
        for (int j = i + 1; j < 5; ++j) row += g[j] * P(at[i], at[j]);
        variance += 2.0 * g[i] * row;
    }
    return variance;
}

double JointStateFilter::unseen_variance(const Parameters& p) {
    const double offset = p.N * p.Kt * p.jsf_current_offset;
    return offset * offset;
}

Matrix<2> JointStateFilter::reading_covariance(double theta_m, double theta_l) {
    // A reading equal to the last one carries the same quantisation error
    // (the angle stayed inside one count), not a fresh one: the k-th repeat's
    // quantisation variance is (1 + kRepeatedReadingWeight*k) q^2/12, so n
    // equal readings say about as much as ln(n)/kRepeatedReadingWeight fresh ones.
    repeats_m_ = started_ && theta_m == last_m_ ? repeats_m_ + 1.0 : 0.0;
    repeats_l_ = started_ && theta_l == last_l_ ? repeats_l_ + 1.0 : 0.0;
    last_m_ = theta_m;
    last_l_ = theta_l;
    Matrix<2> R = R_;
    R(0, 0) += kRepeatedReadingWeight * repeats_m_ * quantisation_m_;
    R(1, 1) += kRepeatedReadingWeight * repeats_l_ * quantisation_l_;
    return R;
}

Matrix<2> JointStateFilter::timing_covariance() const {
    // A reading taken dt after its sample moves both angles along their rates
    // v = (theta_m', theta_l'): variance jsf_r_time^2 * v v^T. The torsion
    // (theta_m/N - theta_l) moves only with its own rate nu, so the readings'
    // common motion is discounted and the torsion kept.
    using namespace joint_state;
    const JointState& x = kalman_.state();
    const Vector<2> v(p_.N * (x(kOmegaL) + x(kNu)), x(kOmegaL));
    return (p_.jsf_r_time * p_.jsf_r_time) * (v * v.transpose());
}

double JointStateFilter::gate(const Vector<2>& z) const {
    // A filter told its readings are exact (no quantisation, no noise) has
    // NIS in the millions on a model error of a micro-radian: only an
    // innovation that is also large in angle can be an outlier.
    if (readings_rejected_) return std::numeric_limits<double>::infinity();
    const Vector<2> v = z - measurement_.h(kalman_.state());
    const double angle = std::max(std::fabs(v(0)) / p_.N, std::fabs(v(1)));
    return angle > kOutlierAngle ? kOutlierGate : std::numeric_limits<double>::infinity();
}

FilterStatus JointStateFilter::step(double theta_m, double theta_l, const JointInput& in, double age) {
    using namespace joint_state;
    measurement_.age = std::isfinite(age) ? age : 0.0;
    const bool readable = std::isfinite(theta_m) && std::isfinite(theta_l);
    const Vector<2> z(theta_m + offset_m_, theta_l + offset_l_);
    FilterStatus status = FilterStatus::Ok;
    UnscentedKalmanFilter<kJointStates>::Update<2> update;
    const Matrix<2> R = readable ? reading_covariance(theta_m, theta_l) : R_;
    if (!started_) {
        if (!readable || !finite(in)) return FilterStatus::SampleRejected;  // nothing to start from
        // At rest, in static balance: the link load holds the torque the torsion shows.
        JointState& x = kalman_.state();
        x.setZero();
        x(kThetaL) = theta_l + offset_l_;
        x(kDelta) = (theta_m + offset_m_) / p_.N - x(kThetaL);
        const JointTorque T = joint_state_torque(x, in, p_);
        x(kLoad) = T.valid ? T.tau - p_.mgl * std::sin(x(kThetaL)) : 0.0;
        kalman_.covariance() = kalman_.initial_covariance();
        record_.predicted = false;
        record_.F.setIdentity();
        record_prior();
        update = kalman_.update(measurement_, z, R);  // at rest: no timing term
        accepted_ = in;
        started_ = true;
    } else {
        // Only the state and covariance change in a prediction and update;
        // the last record holds them as they were (load() keeps it so).
        average_friction_over_speed();
        const JointCovariance Q = process_noise();
        status = kalman_.predict(system_, previous_, Q);
        record_prior();
        update = readable ? kalman_.update(measurement_, z, R + timing_covariance(), gate(z)) : decltype(update){};
        if (!readable || update.status == FilterStatus::SampleRejected) {
            // The current held since the last sample may be the outlier:
            // predict again with the last one that passed; if the readings
            // still fail, only predict (P grows, and so does tau_std).
            const double rejected_nis = update.nis;
            kalman_.state() = record_.x;
            kalman_.covariance() = record_.P;
            status = std::max(status, kalman_.predict(system_, accepted_, Q));
            record_prior();
            if (readable) update = kalman_.update(measurement_, z, R + timing_covariance(), gate(z));
            readings_rejected_ = readable && update.status == FilterStatus::SampleRejected;
            update.nis = rejected_nis;
            update.status = FilterStatus::SampleRejected;
        } else {
            accepted_ = previous_;
            readings_rejected_ = false;
        }
        record_.predicted = true;
        record_.F = kalman_.transition();
    }
    record_.x = kalman_.state();
    record_.P = kalman_.covariance();
    if (finite(in)) current_change_ = std::fabs(in.i_m - previous_.i_m);
    samples_held_ = 0.0;
    previous_ = finite(in) ? in : accepted_;
    follow_hysteresis(!record_.predicted);
    record_.input = previous_;

    // No torque explains this state: the last one is kept, and said so.
    if (!publish_state()) status = std::max(status, FilterStatus::SampleRejected);
    out_.nis = update.nis;
    if (adapt_weight_ > 0.0 && update.status == FilterStatus::Ok)
        load_noise_scale_ += adapt_weight_ * (0.5 * update.nis - load_noise_scale_);
    if (!finite(in)) status = std::max(status, FilterStatus::SampleRejected);
    return std::max(status, update.status);
}

void JointStateFilter::record_prior() {
    record_.x_prior = kalman_.state();
    record_.P_prior = kalman_.covariance();
}

void JointStateFilter::follow_hysteresis(bool first) {
    using namespace joint_state;
    if (!(p_.hys_H > 0.0)) return;
    const JointState& x = kalman_.state();
    const double theta_l = x(kThetaL);
    // The plant's law: the torsion less the kinematic error's (geometry, no strain).
    const double y = x(kDelta) - kinematic_error(p_.N * (theta_l + x(kDelta)), theta_l, p_);
    if (!first) {
        hysteresis_ = dahl_update(hysteresis_, y - torsion_, p_.hys_H, p_.hys_sigma);
        if (y != torsion_) direction_ = y > torsion_ ? 1.0 : -1.0;
    }
    torsion_ = y;
    previous_.z = hysteresis_;
    previous_.dz = p_.hys_sigma * (1.0 - direction_ * hysteresis_ / p_.hys_H);
}

bool JointStateFilter::publish_state() {
    const JointTorque T = system_.torque(kalman_.state(), previous_);
    if (T.valid) {
        out_.tau = T.tau;
        out_.tau_std = std::sqrt(std::max(torque_variance(T, kalman_.covariance()), 0.0) + unseen_variance(p_));
    }
    out_.load = kalman_.state()(joint_state::kLoad);
    return T.valid;
}

void JointStateFilter::predict_without_reading(const JointInput& in) {
    using namespace joint_state;
    if (!started_) return;
    samples_held_ += 1.0;
    average_friction_over_speed();
    JointCovariance Q = process_noise();
    const double a = p_.Kt * samples_held_ * current_change_ / (p_.N * p_.Jm);
    Q(kDelta, kDelta) += a * a * std::pow(0.5 * p_.Ts * p_.Ts, 2);
    Q(kDelta, kNu) += a * a * 0.5 * p_.Ts * p_.Ts * p_.Ts;
    Q(kNu, kDelta) = Q(kDelta, kNu);
    Q(kNu, kNu) += a * a * p_.Ts * p_.Ts;
    kalman_.predict(system_, previous_, Q);
    record_prior();
    record_.predicted = true;
    record_.F = kalman_.transition();
    record_.x = kalman_.state();
    record_.P = kalman_.covariance();
    previous_ = finite(in) ? in : accepted_;
    follow_hysteresis(false);
    record_.input = previous_;
    publish_state();
    out_.nis = 0.0;  // no innovation
}

// [started, x (kJointStates), P (kJointStates^2, column-major), previous and accepted input (i_m, z, t, dz
//  each), outputs (tau, tau_std, load, nis), load noise scale, readings rejected, current change, samples held,
//  last readings (theta_m, theta_l), their repeats, hysteresis torque, its torsion and direction]
void JointStateFilter::save(std::vector<double>* out) const {
    out->push_back(started_ ? 1.0 : 0.0);
    const JointState& x = kalman_.state();
    const JointCovariance& P = kalman_.covariance();
    out->insert(out->end(), x.data(), x.data() + kJointStates);
    out->insert(out->end(), P.data(), P.data() + kJointStates * kJointStates);
    out->insert(out->end(), {previous_.i_m, previous_.z, previous_.t, previous_.dz, accepted_.i_m, accepted_.z,
                             accepted_.t, accepted_.dz, out_.tau, out_.tau_std, out_.load, out_.nis,
                             load_noise_scale_, readings_rejected_ ? 1.0 : 0.0, current_change_, samples_held_,
                             last_m_, last_l_, repeats_m_, repeats_l_, hysteresis_, torsion_, direction_});
}

bool JointStateFilter::load(const std::vector<double>& in, std::size_t* cursor) {
    if (in.size() < *cursor + kSavedSize) return false;
    const double* d = in.data() + *cursor;
    const double* r = d + 1 + kJointStates + kJointStates * kJointStates;
    if ((d[0] != 0.0 && d[0] != 1.0) || (r[13] != 0.0 && r[13] != 1.0) || !(r[14] >= 0.0) || !(r[15] >= 0.0) ||
        !(r[18] >= 0.0) || !(r[19] >= 0.0) || !(r[22] == 0.0 || std::fabs(r[22]) == 1.0))
        return false;
    started_ = d[0] == 1.0;
    std::copy(d + 1, d + 1 + kJointStates, kalman_.state().data());
    std::copy(d + 1 + kJointStates, d + 1 + kJointStates + kJointStates * kJointStates, kalman_.covariance().data());
    previous_ = {r[0], r[1], r[2], r[3]};
    accepted_ = {r[4], r[5], r[6], r[7]};
    out_ = {r[8], r[9], r[10], r[11]};
    load_noise_scale_ = r[12];
    readings_rejected_ = r[13] == 1.0;
    current_change_ = r[14];
    samples_held_ = r[15];
    last_m_ = r[16];
    last_l_ = r[17];
    repeats_m_ = r[18];
    repeats_l_ = r[19];
    hysteresis_ = r[20];
    torsion_ = r[21];
    direction_ = r[22];
    record_.x = kalman_.state();  // where the next step starts over from if it rejects a sample
    record_.P = kalman_.covariance();
    *cursor += kSavedSize;
    return true;
}

void flatten_record(const JointFilterRecord& r, double* out) {
    out = std::copy(r.x_prior.data(), r.x_prior.data() + r.x_prior.size(), out);
    out = std::copy(r.P_prior.data(), r.P_prior.data() + r.P_prior.size(), out);
    out = std::copy(r.F.data(), r.F.data() + r.F.size(), out);
    out = std::copy(r.x.data(), r.x.data() + r.x.size(), out);
    out = std::copy(r.P.data(), r.P.data() + r.P.size(), out);
    *out++ = r.input.i_m;
    *out++ = r.input.z;
    *out++ = r.input.t;
    *out++ = r.input.dz;
    *out = r.predicted ? 1.0 : 0.0;
}

JointFilterRecord unflatten_record(const double* in) {
    JointFilterRecord r;
    auto take = [&in](auto& m) {
        std::copy(in, in + m.size(), m.data());
        in += m.size();
    };
    take(r.x_prior);
    take(r.P_prior);
    take(r.F);
    take(r.x);
    take(r.P);
    r.input = {in[0], in[1], in[2], in[3]};
    r.predicted = in[4] == 1.0;
    return r;
}

RtsBackward::Torque RtsBackward::step(const JointFilterRecord& r) {
    JointState xs = r.x;
    JointCovariance Ps = r.P;
    if (has_next_) {
        Eigen::LLT<JointCovariance> llt(next_.P_prior);
        if (next_.predicted && llt.info() == Eigen::Success && next_.P_prior.allFinite()) {
            // C = P F^T Pprior^-1, as the transpose of Pprior^-1 F P.
            const JointCovariance C = llt.solve(JointCovariance(next_.F * r.P)).transpose();
            xs = r.x + C * (xs_ - next_.x_prior);
            Ps = r.P + C * (Ps_ - next_.P_prior) * C.transpose();
            symmetrize(&Ps);
        }
    }
    xs_ = xs;
    Ps_ = Ps;
    next_ = r;
    has_next_ = true;
    const auto torque = [this, &r](const JointState& x, const JointCovariance& P) -> Torque {
        const JointTorque T = joint_state_torque(x, r.input, p_);
        if (!T.valid) return {std::nan(""), std::nan("")};
        return {T.tau, std::sqrt(std::max(JointStateFilter::torque_variance(T, P), 0.0) +
                                 JointStateFilter::unseen_variance(p_))};
    };
    Torque t = torque(xs_, Ps_);
    if (!std::isfinite(t.tau)) t = torque(r.x, r.P);
    if (!std::isfinite(t.tau)) t = given_;
    given_ = t;
    return t;
}

SmoothedTorque smooth_joint_states(const std::vector<JointFilterRecord>& records, const Parameters& p) {
    SmoothedTorque s;
    const std::size_t n = records.size();
    s.tau.resize(n);
    s.tau_std.resize(n);
    RtsBackward backward(p);
    for (std::size_t j = n; j-- > 0;) {
        const RtsBackward::Torque t = backward.step(records[j]);
        s.tau[j] = t.tau;
        s.tau_std[j] = t.tau_std;
    }
    return s;
}

}  // namespace hdjoint
