#include "joint_state_filter.h"

#include <algorithm>
#include <cmath>

#include "friction.h"
#include "transmission.h"

namespace hdjoint {

namespace {
constexpr double kTwoPi = 6.283185307179586;
// Variance floor of an encoder reading with neither quantisation nor noise, rad^2.
constexpr double kMinReadingVariance = 1e-24;
// Initial spread of the states the first reading does not fix (link speed,
// torsion rate in rad/s; angles in rad); the first update then sets them.
constexpr double kP0Angle = 1e-2, kP0Torsion = 1e-3, kP0Speed = 0.1;

double resolution(double counts) { return counts > 0.0 ? kTwoPi / counts : 0.0; }
}  // namespace

JointTorque joint_state_torque(const JointState& x, const JointInput& in, const Parameters& p) {
    JointTorque t;
    const double theta_l = x(0), theta_m = p.N * (x(0) + x(2));
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
    double e_m = 0.0, e_l = 0.0;
    kinematic_error_gradient(theta_m, theta_l, p, &e_m, &e_l);
    t.tau = c.tau + in.z;
    t.d_delta = k * (1.0 - p.N * e_m);
    t.d_theta_l = k * (-p.N * e_m - e_l);
    t.valid = std::isfinite(t.tau);
    return t;
}

JointTorque JointSystemModel::torque(const State& x, const Control& u) const {
    if (!(cached_ && x == cached_x_ && u.i_m == cached_u_.i_m && u.z == cached_u_.z && u.t == cached_u_.t)) {
        cached_torque_ = joint_state_torque(x, u, p);
        cached_x_ = x;
        cached_u_ = u;
        cached_ = true;
    }
    return cached_torque_;
}

bool JointSystemModel::derivative(const State& x, const Control& u, State* dx, JointCovariance* J) const {
    const Parameters& q = p;
    const JointTorque T = torque(x, u);
    if (!T.valid) return false;
    const double theta_l = x(0), omega_l = x(1), nu = x(3), w = x(4);
    const double theta_m = q.N * (x(0) + x(2)), omega_m = q.N * (omega_l + nu);
    const double scale = friction_drift_scale(u.t, q);
    const double NJm = q.N * q.Jm;
    const double a_l = (T.tau - q.jsf_Bl * omega_l - q.jsf_mgl * std::sin(theta_l) - w) / q.jsf_Jl;
    const double a_m = (motor_torque(u.i_m, theta_m, q) - motor_friction(omega_m, q, scale) - T.tau / q.N) / NJm;
    *dx << omega_l, a_l, nu, a_m - a_l, x(5), 0.0;

    const double cog = cogging_on(q) ? cogging_slope(theta_m, q) : 0.0;  // d/d theta_m
    const double friction = coulomb_friction_slope(omega_m, q, scale) + q.Bm;  // d/d omega_m
    J->setZero();
    (*J)(0, 1) = 1.0;
    (*J)(1, 0) = (T.d_theta_l - q.jsf_mgl * std::cos(theta_l)) / q.jsf_Jl;
    (*J)(1, 1) = -q.jsf_Bl / q.jsf_Jl;
    (*J)(1, 2) = T.d_delta / q.jsf_Jl;
    (*J)(1, 4) = -1.0 / q.jsf_Jl;
    (*J)(2, 3) = 1.0;
    const double am_theta_l = (cog * q.N - T.d_theta_l / q.N) / NJm;
    const double am_speed = -friction * q.N / NJm;  // by omega_l and by nu
    const double am_delta = (cog * q.N - T.d_delta / q.N) / NJm;
    (*J)(3, 0) = am_theta_l - (*J)(1, 0);
    (*J)(3, 1) = am_speed - (*J)(1, 1);
    (*J)(3, 2) = am_delta - (*J)(1, 2);
    (*J)(3, 3) = am_speed;
    (*J)(3, 4) = -(*J)(1, 4);
    (*J)(4, 5) = 1.0;
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
    // M = I - c*J, c = h/2. J's rows 0, 2, 4 are the kinematic identities
    // (d theta_l = omega_l, d delta = nu, d w = r) and row 5 is zero, so
    // M z = y reduces to a 2x2 system in (z1, z3): solved in closed form
    // (the same numbers as a general LU up to round-off, at a fraction of its cost).
    const double c = 0.5 * h;
    const double a11 = 1.0 - c * c * J(1, 0) - c * J(1, 1), a13 = -c * c * J(1, 2) - c * J(1, 3);
    const double a31 = -c * c * J(3, 0) - c * J(3, 1), a33 = 1.0 - c * c * J(3, 2) - c * J(3, 3);
    const double det = a11 * a33 - a13 * a31;
    auto solve = [&](const State& y) {
        State z;
        z(5) = y(5);
        z(4) = y(4) + c * z(5);
        const double r1 = y(1) + c * (J(1, 0) * y(0) + J(1, 2) * y(2) + J(1, 4) * z(4) + J(1, 5) * z(5));
        const double r3 = y(3) + c * (J(3, 0) * y(0) + J(3, 2) * y(2) + J(3, 4) * z(4) + J(3, 5) * z(5));
        z(1) = (a33 * r1 - a13 * r3) / det;
        z(3) = (a11 * r3 - a31 * r1) / det;
        z(0) = y(0) + c * z(1);
        z(2) = y(2) + c * z(3);
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
    system_.p = p;
    system_.h = p.Ts;
    measurement_.N = p.N;
    // The current noise and the unmodelled motor torque, as a motor-side
    // torque held over the sample: an acceleration on nu.
    const double torque_std = std::hypot(p.Kt * p.jsf_current_noise, p.jsf_q_motor);
    const double a = torque_std / (p.N * p.Jm);
    JointState G;
    G << 0.0, 0.0, 0.5 * p.Ts * p.Ts, p.Ts, 0.0, 0.0;
    Q_ = (a * a) * (G * G.transpose());
    Q_(4, 4) = p.jsf_q_load * p.jsf_q_load;
    Q_(5, 5) = p.jsf_q_load_rate * p.jsf_q_load_rate;
    // Floor quantisers: reading + q/2 is unbiased, variance q^2/12.
    const double qm = resolution(p.jsf_motor_counts), ql = resolution(p.jsf_link_counts);
    offset_m_ = 0.5 * qm;
    offset_l_ = 0.5 * ql;
    R_.setZero();
    R_(0, 0) = std::max(p.jsf_r_theta_m * p.jsf_r_theta_m + qm * qm / 12.0, kMinReadingVariance);
    R_(1, 1) = std::max(p.jsf_r_theta_l * p.jsf_r_theta_l + ql * ql / 12.0, kMinReadingVariance);
    JointCovariance P0 = JointCovariance::Zero();
    P0.diagonal() << kP0Angle * kP0Angle, kP0Speed * kP0Speed, kP0Torsion * kP0Torsion, kP0Speed * kP0Speed,
        p.jsf_p0_load * p.jsf_p0_load, p.jsf_p0_load * p.jsf_p0_load;  // load rate: jsf_p0_load per second
    ukf_ = UnscentedKalmanFilter<kJointStates>(merwe_weights<kJointStates>(1.0, 2.0, 0.0), JointState::Zero(), P0);
}

FilterStatus JointStateFilter::step(double theta_m, double theta_l, const JointInput& in) {
    FilterStatus predicted = FilterStatus::Ok;
    if (!started_) {
        // At rest, in static balance: the link load holds the torque the torsion shows.
        JointState& x = ukf_.state();
        x.setZero();
        x(0) = theta_l + offset_l_;
        x(2) = (theta_m + offset_m_) / p_.N - x(0);
        const JointTorque T = joint_state_torque(x, in, p_);
        x(4) = T.valid ? T.tau - p_.jsf_mgl * std::sin(x(0)) : 0.0;
        ukf_.covariance() = ukf_.initial_covariance();
        record_.predicted = false;
        record_.F.setIdentity();
        started_ = true;
    } else {
        predicted = ukf_.predict(system_, previous_, Q_);
        record_.predicted = true;
        record_.F = ukf_.transition();
    }
    record_.x_prior = ukf_.state();
    record_.P_prior = ukf_.covariance();
    const Vector<2> z(theta_m + offset_m_, theta_l + offset_l_);
    const auto update = ukf_.update(measurement_, z, R_);
    record_.x = ukf_.state();
    record_.P = ukf_.covariance();
    record_.input = in;
    previous_ = in;

    const JointTorque T = system_.torque(ukf_.state(), in);
    const JointCovariance& P = ukf_.covariance();
    out_.tau = T.valid ? T.tau : out_.tau;
    const double var = T.d_theta_l * T.d_theta_l * P(0, 0) + 2.0 * T.d_theta_l * T.d_delta * P(0, 2) +
                       T.d_delta * T.d_delta * P(2, 2);
    out_.tau_std = std::sqrt(std::max(var, 0.0));
    out_.load = ukf_.state()(4);
    out_.nis = update.nis;
    return std::max(predicted, update.status);
}

// [started, x (5), P (25, column-major), previous input (i_m, z, t), outputs (tau, tau_std, load, nis)]
void JointStateFilter::save(std::vector<double>* out) const {
    out->push_back(started_ ? 1.0 : 0.0);
    const JointState& x = ukf_.state();
    const JointCovariance& P = ukf_.covariance();
    out->insert(out->end(), x.data(), x.data() + kJointStates);
    out->insert(out->end(), P.data(), P.data() + kJointStates * kJointStates);
    out->insert(out->end(), {previous_.i_m, previous_.z, previous_.t, out_.tau, out_.tau_std, out_.load, out_.nis});
}

bool JointStateFilter::load(const std::vector<double>& in, std::size_t* cursor) {
    if (in.size() < *cursor + kSavedSize) return false;
    const double* d = in.data() + *cursor;
    if (d[0] != 0.0 && d[0] != 1.0) return false;
    started_ = d[0] == 1.0;
    std::copy(d + 1, d + 1 + kJointStates, ukf_.state().data());
    std::copy(d + 1 + kJointStates, d + 1 + kJointStates + kJointStates * kJointStates, ukf_.covariance().data());
    const double* r = d + 1 + kJointStates + kJointStates * kJointStates;
    previous_ = {r[0], r[1], r[2]};
    out_ = {r[3], r[4], r[5], r[6]};
    *cursor += kSavedSize;
    return true;
}

SmoothedTorque smooth_joint_states(const std::vector<JointFilterRecord>& records, const Parameters& p) {
    SmoothedTorque s;
    const std::size_t n = records.size();
    s.tau.resize(n);
    s.tau_std.resize(n);
    if (n == 0) return s;
    JointState xs = records[n - 1].x;
    JointCovariance Ps = records[n - 1].P;
    for (std::size_t j = n; j-- > 0;) {
        const JointFilterRecord& r = records[j];
        if (j + 1 < n) {
            const JointFilterRecord& next = records[j + 1];
            Eigen::LLT<JointCovariance> llt(next.P_prior);
            if (next.predicted && llt.info() == Eigen::Success && next.P_prior.allFinite()) {
                // C = P F^T Pprior^-1, as the transpose of Pprior^-1 F P.
                const JointCovariance C = llt.solve(JointCovariance(next.F * r.P)).transpose();
                xs = r.x + C * (xs - next.x_prior);
                Ps = r.P + C * (Ps - next.P_prior) * C.transpose();
                symmetrize(&Ps);
            } else {
                xs = r.x;
                Ps = r.P;
            }
        }
        const JointTorque T = joint_state_torque(xs, r.input, p);
        s.tau[j] = T.valid ? T.tau : std::nan("");
        const double var = T.d_theta_l * T.d_theta_l * Ps(0, 0) + 2.0 * T.d_theta_l * T.d_delta * Ps(0, 2) +
                           T.d_delta * T.d_delta * Ps(2, 2);
        s.tau_std[j] = std::sqrt(std::max(var, 0.0));
    }
    return s;
}

}  // namespace hdjoint
