// The generic UKF (ukf.h), its sigma points (sigma_points.h) and the
// covariance factorisation (linear_algebra.h).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "linear_algebra.h"
#include "sigma_points.h"
#include "ukf.h"

namespace hdjoint {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The symmetric part, written element by element (exactly symmetric).
template <int N>
Matrix<N> exactly_symmetric(const Matrix<N>& A) {
    Matrix<N> S;
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) S(i, j) = 0.5 * (A(i, j) + A(j, i));
    return S;
}

template <int N>
double asymmetry(const Matrix<N>& P) {
    return (P - P.transpose()).cwiseAbs().maxCoeff();
}

template <int N>
Matrix<N> random_spd(std::mt19937* rng, double min_eigenvalue = 0.1) {
    std::normal_distribution<double> g(0.0, 1.0);
    Matrix<N> A;
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) A(i, j) = g(*rng);
    Matrix<N> P = A * A.transpose();
    P.diagonal().array() += min_eigenvalue;
    return exactly_symmetric(P);
}

// ---- linear models --------------------------------------------------------

template <int NX>
struct LinearSystem {
    using State = Vector<NX>;
    using Control = double;
    Matrix<NX> F;
    Vector<NX> B;
    State f(const State& x, Control u) const { return F * x + B * u; }
};

// The same system declaring itself linear: the UKF may then propagate it
// exactly (F P F' + Q) instead of through sigma points.
template <int NX>
struct DeclaredLinearSystem : LinearSystem<NX> {
    static constexpr bool kLinear = true;
    Matrix<NX> transition() const { return this->F; }
};

template <int NX, int NZ>
struct LinearMeasurement {
    static constexpr int kSize = NZ;
    using Vector = hdjoint::Vector<NZ>;
    using Covariance = Matrix<NZ>;
    Eigen::Matrix<double, NZ, NX> H;
    Vector h(const hdjoint::Vector<NX>& x) const { return H * x; }
};

// The textbook linear Kalman filter the UKF must reproduce on linear models.
template <int NX, int NZ>
struct KalmanFilter {
    Vector<NX> x;
    Matrix<NX> P;
    void predict(const LinearSystem<NX>& s, double u, const Matrix<NX>& Q) {
        x = s.F * x + s.B * u;
        P = s.F * P * s.F.transpose() + Q;
    }
    double update(const LinearMeasurement<NX, NZ>& m, const Vector<NZ>& z, const Matrix<NZ>& R) {
        const Vector<NZ> y = z - m.H * x;
        const Matrix<NZ> S = m.H * P * m.H.transpose() + R;
        const Eigen::Matrix<double, NX, NZ> K = P * m.H.transpose() * S.inverse();
        x += K * y;
        const Matrix<NX> I_KH = Matrix<NX>::Identity() - K * m.H;
        P = I_KH * P * I_KH.transpose() + K * R * K.transpose();  // Joseph form
        return y.dot(S.inverse() * y);
    }
};

template <int NX, int NZ, class System = LinearSystem<NX>>
void expect_ukf_equals_kalman_filter(double alpha, double beta, double kappa) {
    std::mt19937 rng(42 + NX * 10 + NZ);
    std::normal_distribution<double> g(0.0, 1.0);

    System sys;
    sys.F = Matrix<NX>::Identity() * 0.95;
    for (int i = 0; i + 1 < NX; ++i) sys.F(i, i + 1) = 0.1;  // coupled, stable
    sys.F(NX - 1, 0) = -0.05;
    for (int i = 0; i < NX; ++i) sys.B(i) = 0.3 + 0.1 * i;
    LinearMeasurement<NX, NZ> meas;
    for (int i = 0; i < NZ; ++i)
        for (int j = 0; j < NX; ++j) meas.H(i, j) = g(rng);
    const Matrix<NX> Q = random_spd<NX>(&rng, 0.01) * 0.01;
    const Matrix<NZ> R = random_spd<NZ>(&rng, 0.1) * 0.1;

    Vector<NX> x0;
    for (int i = 0; i < NX; ++i) x0(i) = g(rng);
    const Matrix<NX> P0 = random_spd<NX>(&rng, 0.5);

    UnscentedKalmanFilter<NX> ukf(merwe_weights<NX>(alpha, beta, kappa), x0, P0);
    KalmanFilter<NX, NZ> kf{x0, P0};
    Vector<NX> truth = x0;
    for (int k = 0; k < 300; ++k) {
        const double u = std::sin(0.05 * k);
        truth = sys.f(truth, u);
        for (int i = 0; i < NX; ++i) truth(i) += 0.1 * g(rng);
        Vector<NZ> z = meas.h(truth);
        for (int i = 0; i < NZ; ++i) z(i) += 0.3 * g(rng);

        ASSERT_EQ(ukf.predict(sys, u, Q), FilterStatus::Ok) << k;
        kf.predict(sys, u, Q);
        ASSERT_LT((ukf.state() - kf.x).norm(), 1e-10 * (1.0 + kf.x.norm())) << "predict " << k;
        ASSERT_LT((ukf.covariance() - kf.P).norm(), 1e-10 * kf.P.norm()) << "predict " << k;

        const Vector<NZ> innovation = z - meas.H * kf.x;
        const auto upd = ukf.update(meas, z, R);
        const double nis = kf.update(meas, z, R);
        ASSERT_EQ(upd.status, FilterStatus::Ok) << k;
        ASSERT_LT((ukf.state() - kf.x).norm(), 1e-10 * (1.0 + kf.x.norm())) << "update " << k;
        ASSERT_LT((ukf.covariance() - kf.P).norm(), 1e-10 * kf.P.norm()) << "update " << k;
        ASSERT_LT((upd.innovation - innovation).norm(), 1e-10 * (1.0 + innovation.norm())) << k;
        ASSERT_NEAR(upd.nis, nis, 1e-9 * (1.0 + nis)) << k;
        // Symmetric (exactness is Ukf.CovarianceStaysSymmetricOnANonlinearModel's business).
        ASSERT_LE(asymmetry<NX>(ukf.covariance()), 1e-15 * ukf.covariance().norm()) << k;
    }
    // The filter actually tracked something (the comparison is not between two idle filters).
    EXPECT_GT(kf.x.norm(), 0.1);
}

TEST(Ukf, EqualsLinearKalmanFilter2States2Measurements) { expect_ukf_equals_kalman_filter<2, 2>(1.0, 2.0, 1.0); }
TEST(Ukf, EqualsLinearKalmanFilter3States2Measurements) { expect_ukf_equals_kalman_filter<3, 2>(1.0, 2.0, 0.0); }
TEST(Ukf, EqualsLinearKalmanFilter4States1MeasurementSmallAlpha) {
    expect_ukf_equals_kalman_filter<4, 1>(0.5, 2.0, 0.0);
}
TEST(Ukf, LinearFastPathEqualsLinearKalmanFilter) {
    expect_ukf_equals_kalman_filter<2, 2, DeclaredLinearSystem<2>>(1.0, 2.0, 1.0);
    expect_ukf_equals_kalman_filter<3, 2, DeclaredLinearSystem<3>>(0.5, 2.0, 0.0);
}

TEST(Ukf, InnovationAndItsCovarianceAreReported) {
    const Vector<2> x0(1.0, -2.0);
    Matrix<2> P0;
    P0 << 2.0, 0.3, 0.3, 1.0;
    UnscentedKalmanFilter<2> ukf(merwe_weights<2>(1.0, 2.0, 1.0), x0, P0);
    LinearMeasurement<2, 1> m;
    m.H << 1.0, 2.0;
    Matrix<1> R;
    R << 0.5;
    Vector<1> z;
    z << 4.0;
    const auto upd = ukf.update(m, z, R);
    ASSERT_EQ(upd.status, FilterStatus::Ok);
    // z_hat = 1 - 4 = -3; S = H P H' + R = 2 + 4*0.3 + 4 + 0.5 = 7.7
    EXPECT_NEAR(upd.innovation(0), 7.0, 1e-12);
    EXPECT_NEAR(upd.innovation_covariance(0, 0), 7.7, 1e-12);
    EXPECT_NEAR(upd.nis, 49.0 / 7.7, 1e-12);
}

// ---- nonlinear / degenerate models ---------------------------------------

struct Pendulum {
    using State = Vector<3>;
    using Control = double;
    State f(const State& x, double u) const {
        State n;
        n << x(0) + 0.01 * x(1), x(1) - 0.01 * (std::sin(x(0)) + 0.1 * x(1)) + u, 0.99 * x(2) + 0.1 * x(0) * x(1);
        return n;
    }
};
struct Polar {
    static constexpr int kSize = 2;
    using Vector = hdjoint::Vector<2>;
    using Covariance = Matrix<2>;
    Vector h(const hdjoint::Vector<3>& x) const { return Vector(std::atan2(x(1), 1.0 + x(0) * x(0)), x(2) * x(2)); }
};

// A measurement that does not depend on the state.
struct Constant {
    static constexpr int kSize = 1;
    using Vector = hdjoint::Vector<1>;
    using Covariance = Matrix<1>;
    Vector h(const hdjoint::Vector<2>&) const { return Vector(3.0); }
};

TEST(Ukf, CovarianceStaysSymmetricOnANonlinearModel) {
    std::mt19937 rng(7);
    UnscentedKalmanFilter<3> ukf(merwe_weights<3>(0.3, 2.0, 0.0), Vector<3>(0.5, 0.0, 1.0), random_spd<3>(&rng));
    const Matrix<3> Q = Matrix<3>::Identity() * 1e-4;
    const Matrix<2> R = Matrix<2>::Identity() * 1e-2;
    for (int k = 0; k < 200; ++k) {
        ukf.predict(Pendulum{}, 0.001 * std::cos(0.1 * k), Q);
        ASSERT_EQ(asymmetry<3>(ukf.covariance()), 0.0) << "after predict " << k;
        ukf.update(Polar{}, Vector<2>(0.1 * std::sin(0.05 * k), 1.0), R);
        ASSERT_EQ(asymmetry<3>(ukf.covariance()), 0.0) << "after update " << k;
        ASSERT_TRUE(ukf.state().allFinite());
        Eigen::LLT<Matrix<3>> llt(ukf.covariance());
        ASSERT_EQ(llt.info(), Eigen::Success) << k;
    }
}

// ---- symmetrize and robust_cholesky ------------------------------------------

// Regression (fixed in 7135e36): `*P = 0.5 * (*P + P->transpose())` aliased:
// Eigen evaluated it in place, so P(j,i) was computed from the already
// overwritten P(i,j); [[1,2],[0,1]] became [[1,1.5],[1,1]] instead of
// [[1,1],[1,1]] and the UKF's covariances were not kept symmetric.
TEST(LinearAlgebra, SymmetrizeGivesTheSymmetricPart) {
    Matrix<2> P;
    P << 1.0, 2.0, 0.0, 1.0;
    symmetrize(&P);
    Matrix<2> expected;
    expected << 1.0, 1.0, 1.0, 1.0;
    EXPECT_EQ(P, expected) << P;

    Matrix<3> Q;
    Q << 1.0, 2.0, 3.0, 0.0, 1.0, 4.0, 0.0, 0.0, 1.0;
    const Matrix<3> Q_expected = exactly_symmetric<3>(Q);
    symmetrize(&Q);
    EXPECT_EQ(Q, Q_expected) << Q;
    EXPECT_EQ(asymmetry<3>(Q), 0.0);

    Matrix<3> S = Q_expected;  // already symmetric: unchanged
    symmetrize(&S);
    EXPECT_EQ(S, Q_expected);
}

TEST(RobustCholesky, OkOnSpdMatrices) {
    std::mt19937 rng(1);
    for (int trial = 0; trial < 50; ++trial) {
        Matrix<3> P = random_spd<3>(&rng), L;
        const Matrix<3> original = P;
        ASSERT_EQ(robust_cholesky<3>(&P, &L), FactorStatus::Ok);
        EXPECT_EQ(P, original);
        EXPECT_LT((L * L.transpose() - P).norm(), 1e-12 * P.norm());
        EXPECT_EQ(L(0, 1), 0.0);
        EXPECT_EQ(L(0, 2), 0.0);
        EXPECT_EQ(L(1, 2), 0.0);
    }
}

template <int N>
void expect_repairs_slightly_indefinite() {
    std::mt19937 rng(11 + N);
    for (int trial = 0; trial < 20; ++trial) {
        // P = V diag(lambda) V' with one eigenvalue slightly negative.
        const Matrix<N> A = random_spd<N>(&rng);
        Eigen::SelfAdjointEigenSolver<Matrix<N>> es(A);
        Vector<N> lambda = es.eigenvalues();
        lambda(0) = -1e-9 * lambda(N - 1);
        Matrix<N> P = exactly_symmetric<N>(es.eigenvectors() * lambda.asDiagonal() * es.eigenvectors().transpose());
        ASSERT_NE(Eigen::LLT<Matrix<N>>(P).info(), Eigen::Success);  // really indefinite
        const Matrix<N> before = P;
        Matrix<N> L;
        ASSERT_EQ(robust_cholesky<N>(&P, &L), FactorStatus::Repaired) << trial;
        // The repaired P is positive definite, L is its factor, and it is close to the original.
        EXPECT_EQ(Eigen::LLT<Matrix<N>>(P).info(), Eigen::Success);
        EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix<N>>(P).eigenvalues().minCoeff(), 0.0);
        EXPECT_LT((L * L.transpose() - P).norm(), 1e-12 * P.norm());
        EXPECT_LT((P - before).norm(), 1e-6 * before.norm());
        // Only the diagonal was touched.
        const Matrix<N> diff = P - before;
        EXPECT_EQ((diff - Matrix<N>(diff.diagonal().asDiagonal())).cwiseAbs().maxCoeff(), 0.0);
    }
}

TEST(RobustCholesky, RepairsSlightlyIndefinite2x2) { expect_repairs_slightly_indefinite<2>(); }
TEST(RobustCholesky, RepairsSlightlyIndefinite3x3) { expect_repairs_slightly_indefinite<3>(); }
TEST(RobustCholesky, RepairsSlightlyIndefinite4x4) { expect_repairs_slightly_indefinite<4>(); }

TEST(RobustCholesky, RepairsAZeroPivot2x2) {
    Matrix<2> P, L;
    P << 1.0, 1.0, 1.0, 1.0;  // singular
    ASSERT_EQ(robust_cholesky<2>(&P, &L), FactorStatus::Repaired);
    EXPECT_LT((L * L.transpose() - P).norm(), 1e-12);
    EXPECT_GT(P(1, 1), 1.0);
}

template <int N>
void expect_fails_on_nan_and_strongly_indefinite() {
    Matrix<N> P = Matrix<N>::Identity(), L;
    P(N - 1, 0) = kNaN;
    EXPECT_EQ(robust_cholesky<N>(&P, &L), FactorStatus::Failed);
    P = Matrix<N>::Identity() * kNaN;
    EXPECT_EQ(robust_cholesky<N>(&P, &L), FactorStatus::Failed);
    P = Matrix<N>::Identity();
    P(0, 0) = std::numeric_limits<double>::infinity();
    EXPECT_EQ(robust_cholesky<N>(&P, &L), FactorStatus::Failed);
    P = -Matrix<N>::Identity();  // far from positive definite: no small jitter fixes it
    EXPECT_EQ(robust_cholesky<N>(&P, &L), FactorStatus::Failed);
}

TEST(RobustCholesky, FailsOnNaN2x2) { expect_fails_on_nan_and_strongly_indefinite<2>(); }
TEST(RobustCholesky, FailsOnNaN3x3) { expect_fails_on_nan_and_strongly_indefinite<3>(); }

TEST(RobustCholesky, ClosedForm2x2EqualsEigenLLT) {
    std::mt19937 rng(2024);
    std::uniform_real_distribution<double> scale(-6.0, 6.0);
    for (int trial = 0; trial < 1000; ++trial) {
        Matrix<2> P = random_spd<2>(&rng, 1e-3);
        P *= std::pow(10.0, scale(rng));  // over 12 decades
        Matrix<2> P_closed = P, L_closed;
        ASSERT_EQ(robust_cholesky<2>(&P_closed, &L_closed), FactorStatus::Ok);
        const Eigen::LLT<Matrix<2>> llt(P);
        ASSERT_EQ(llt.info(), Eigen::Success);
        const Matrix<2> L_eigen = llt.matrixL();
        EXPECT_LT((L_closed - L_eigen).cwiseAbs().maxCoeff(), 1e-14 * L_eigen.cwiseAbs().maxCoeff()) << P;
        EXPECT_EQ(L_closed(0, 1), 0.0);
    }
}

// ---- sigma points and the unscented transform -----------------------------

TEST(SigmaPoints, MerweWeights) {
    for (double alpha : {1.0, 0.5, 1e-3}) {
        for (double kappa : {0.0, 1.0}) {
            const auto w = merwe_weights<3>(alpha, 2.0, kappa);
            const double lambda = alpha * alpha * (3.0 + kappa) - 3.0;
            EXPECT_NEAR(w.mean.sum(), 1.0, 1e-9);
            EXPECT_NEAR(w.covariance.sum(), 1.0 + (1.0 - alpha * alpha + 2.0), 1e-9);
            EXPECT_NEAR(w.gamma, std::sqrt(3.0 + lambda), 1e-15);
            EXPECT_NEAR(w.mean(0), lambda / (3.0 + lambda), 1e-9);
            for (int i = 1; i < 7; ++i) EXPECT_NEAR(w.mean(i), 1.0 / (2.0 * (3.0 + lambda)), 1e-6 * w.mean(i));
        }
    }
}

TEST(SigmaPoints, UnscentedTransformIsExactForLinearMaps) {
    std::mt19937 rng(5);
    std::normal_distribution<double> g(0.0, 1.0);
    for (double alpha : {1.0, 0.2, 1e-3}) {
        const auto w = merwe_weights<3>(alpha, 2.0, 0.0);
        Vector<3> m(0.3, -1.0, 2.0);
        Matrix<3> P = random_spd<3>(&rng), L;
        ASSERT_EQ(robust_cholesky<3>(&P, &L), FactorStatus::Ok);
        const SigmaPoints<3> chi = sigma_points<3>(m, L, w.gamma);
        EXPECT_EQ(chi.col(0), m);

        // The points themselves carry the Gaussian's mean and covariance.
        Vector<3> mean;
        Matrix<3> cov;
        unscented_transform<3, 7>(chi, w.mean, w.covariance, &mean, &cov);
        EXPECT_LT((mean - m).norm(), 1e-12 * (1.0 + 1.0 / (alpha * alpha)));
        EXPECT_LT((cov - P).norm(), 1e-10 * P.norm());

        // A linear map y = A x + b: mean A m + b, covariance A P A'.
        Eigen::Matrix<double, 2, 3> A;
        for (int i = 0; i < 2; ++i)
            for (int j = 0; j < 3; ++j) A(i, j) = g(rng);
        const Vector<2> b(5.0, -7.0);
        const Eigen::Matrix<double, 2, 7> Y = (A * chi).colwise() + b;
        Vector<2> my;
        Matrix<2> Py;
        unscented_transform<2, 7>(Y, w.mean, w.covariance, &my, &Py);
        EXPECT_LT((my - (A * m + b)).norm(), 1e-11 * (1.0 + 1.0 / (alpha * alpha)));
        EXPECT_LT((Py - A * P * A.transpose()).norm(), 1e-9 * (A * P * A.transpose()).norm());
    }
}

TEST(SigmaPoints, UnscentedTransformCapturesASquare) {
    // For x ~ N(m, s^2): E[x^2] = m^2 + s^2 (exact with any alpha), Var[x^2] =
    // 4 m^2 s^2 + 2 s^4 (exact with alpha = 1, beta = 0, kappa = 3 - n = 2: the
    // points then match the Gaussian's fourth moment).
    const auto w = merwe_weights<1>(1.0, 0.0, 2.0);
    const double m = 1.5, s = 0.4;
    Matrix<1> L;
    L << s;
    const SigmaPoints<1> chi = sigma_points<1>(Vector<1>(m), L, w.gamma);
    const Eigen::Matrix<double, 1, 3> y = chi.array().square();
    Vector<1> mean;
    Matrix<1> cov;
    unscented_transform<1, 3>(y, w.mean, w.covariance, &mean, &cov);
    EXPECT_NEAR(mean(0), m * m + s * s, 1e-14);
    EXPECT_NEAR(cov(0, 0), 4 * m * m * s * s + 2 * s * s * s * s, 1e-13);
}

// ---- recovery -------------------------------------------------------------

struct Fixture2 {
    LinearSystem<2> sys;
    LinearMeasurement<2, 2> meas;
    Matrix<2> Q = Matrix<2>::Identity() * 1e-3;
    Matrix<2> R = Matrix<2>::Identity() * 1e-2;
    Matrix<2> P0;
    UnscentedKalmanFilter<2> ukf;
    Fixture2() {
        sys.F << 1.0, 0.01, 0.0, 1.0;
        sys.B << 0.0, 0.01;
        meas.H = Matrix<2>::Identity();
        P0 << 2.0, 0.1, 0.1, 3.0;
        ukf = UnscentedKalmanFilter<2>(merwe_weights<2>(1.0, 2.0, 1.0), Vector<2>(1.0, 0.0), P0);
    }
    template <int NX>
    static void run_ok(UnscentedKalmanFilter<NX>* f, const LinearSystem<NX>& s, const LinearMeasurement<NX, NX>& m,
                       const Matrix<NX>& Q, const Matrix<NX>& R, int steps) {
        for (int k = 0; k < steps; ++k) {
            ASSERT_EQ(f->predict(s, 1.0, Q), FilterStatus::Ok);
            ASSERT_EQ(f->update(m, Vector<NX>::Constant(0.5), R).status, FilterStatus::Ok);
        }
    }
};

TEST(UkfRecovery, ResetsNaNCovarianceAndRecovers) {
    Fixture2 t;
    Fixture2::run_ok(&t.ukf, t.sys, t.meas, t.Q, t.R, 5);
    t.ukf.covariance()(0, 1) = kNaN;
    t.ukf.covariance()(1, 0) = kNaN;
    ASSERT_EQ(t.ukf.predict(t.sys, 1.0, t.Q), FilterStatus::CovarianceReset);
    EXPECT_TRUE(t.ukf.state().allFinite());
    EXPECT_TRUE(t.ukf.covariance().allFinite());
    // The reset covariance is P0 propagated once: F P0 F' + Q.
    EXPECT_LT((t.ukf.covariance() - (t.sys.F * t.P0 * t.sys.F.transpose() + t.Q)).norm(), 1e-12);
    // Later updates work and pull the state to the measurement.
    const Vector<2> before = t.ukf.state();
    const auto upd = t.ukf.update(t.meas, Vector<2>(0.5, 0.5), t.R);
    EXPECT_EQ(upd.status, FilterStatus::Ok);
    EXPECT_NE(t.ukf.state(), before);
    Fixture2::run_ok(&t.ukf, t.sys, t.meas, t.Q, t.R, 20);
    EXPECT_TRUE(t.ukf.state().allFinite());
}

TEST(UkfRecovery, ResetsNaNStateAndCovariance) {
    Fixture2 t;
    t.ukf.covariance().setConstant(kNaN);
    t.ukf.state().setConstant(kNaN);
    const auto upd = t.ukf.update(t.meas, Vector<2>(0.5, 0.5), t.R);
    EXPECT_EQ(upd.status, FilterStatus::CovarianceReset);
    EXPECT_TRUE(t.ukf.state().allFinite());
    EXPECT_TRUE(t.ukf.covariance().allFinite());
    // The measurement was used on the reset filter: the state moved from 0 toward z.
    EXPECT_GT(t.ukf.state()(0), 0.4);
    Fixture2::run_ok(&t.ukf, t.sys, t.meas, t.Q, t.R, 20);
}

TEST(UkfRecovery, ResetsIndefiniteCovariance) {
    Fixture2 t;
    t.ukf.covariance() << 1.0, 0.0, 0.0, -1.0;  // far from positive definite
    ASSERT_EQ(t.ukf.predict(t.sys, 1.0, t.Q), FilterStatus::CovarianceReset);
    EXPECT_TRUE(t.ukf.state().allFinite());
    EXPECT_EQ(Eigen::LLT<Matrix<2>>(t.ukf.covariance()).info(), Eigen::Success);
    Fixture2::run_ok(&t.ukf, t.sys, t.meas, t.Q, t.R, 20);
}

TEST(UkfRecovery, RepairsSlightlyIndefiniteCovariance) {
    Fixture2 t;
    t.ukf.covariance() << 1.0, 1.0, 1.0, 1.0 - 1e-12;
    ASSERT_EQ(t.ukf.predict(t.sys, 1.0, t.Q), FilterStatus::CovarianceRepaired);
    EXPECT_EQ(Eigen::LLT<Matrix<2>>(t.ukf.covariance()).info(), Eigen::Success);
    Fixture2::run_ok(&t.ukf, t.sys, t.meas, t.Q, t.R, 5);
}

TEST(UkfRecovery, LinearFastPathResetsNaNCovariance) {
    Fixture2 t;
    DeclaredLinearSystem<2> sys;
    sys.F = t.sys.F;
    sys.B = t.sys.B;
    t.ukf.covariance()(1, 1) = kNaN;
    ASSERT_EQ(t.ukf.predict(sys, 1.0, t.Q), FilterStatus::CovarianceReset);
    EXPECT_TRUE(t.ukf.covariance().allFinite());
    EXPECT_LT((t.ukf.covariance() - (sys.F * t.P0 * sys.F.transpose() + t.Q)).norm(), 1e-12);
    t.ukf.state()(0) = kNaN;
    ASSERT_EQ(t.ukf.predict(sys, 1.0, t.Q), FilterStatus::CovarianceReset);
    EXPECT_TRUE(t.ukf.state().allFinite());
    for (int k = 0; k < 10; ++k) {
        ASSERT_EQ(t.ukf.predict(sys, 1.0, t.Q), FilterStatus::Ok);
        ASSERT_EQ(t.ukf.update(t.meas, Vector<2>(0.5, 0.5), t.R).status, FilterStatus::Ok);
    }
}

TEST(UkfRecovery, ResetInGenericDimension) {
    LinearSystem<3> sys;
    sys.F = Matrix<3>::Identity();
    sys.B = Vector<3>::Constant(0.1);
    LinearMeasurement<3, 3> meas;
    meas.H = Matrix<3>::Identity();
    const Matrix<3> Q = Matrix<3>::Identity() * 1e-3, R = Matrix<3>::Identity() * 1e-2;
    UnscentedKalmanFilter<3> ukf(merwe_weights<3>(1.0, 2.0, 0.0), Vector<3>::Zero(), Matrix<3>::Identity());
    ukf.covariance()(2, 2) = kNaN;
    EXPECT_EQ(ukf.predict(sys, 1.0, Q), FilterStatus::CovarianceReset);
    EXPECT_TRUE(ukf.covariance().allFinite());
    EXPECT_TRUE(ukf.state().allFinite());
    Fixture2::run_ok(&ukf, sys, meas, Q, R, 10);
}

TEST(UkfRecovery, UpdateSkippedWhenInnovationCovarianceIsSingular) {
    // A measurement that does not depend on the state, with no noise: Pzz = 0.
    Fixture2 t;
    const Vector<2> x = t.ukf.state();
    const Matrix<2> P = t.ukf.covariance();
    const auto upd = t.ukf.update(Constant{}, Vector<1>(4.0), Matrix<1>::Zero());
    EXPECT_EQ(upd.status, FilterStatus::UpdateSkipped);
    EXPECT_EQ(t.ukf.state(), x);
    EXPECT_EQ(t.ukf.covariance(), P);
    // And with a negative-definite R (Pzz indefinite).
    Matrix<2> badR = -Matrix<2>::Identity() * 100.0;
    EXPECT_EQ(t.ukf.update(t.meas, Vector<2>(0.5, 0.5), badR).status, FilterStatus::UpdateSkipped);
    EXPECT_EQ(t.ukf.state(), x);
    EXPECT_EQ(t.ukf.covariance(), P);
}

TEST(UkfRecovery, UpdateSkippedWhenNoiseOrMeasurementIsNaN) {
    Fixture2 t;
    const Vector<2> x = t.ukf.state();
    const Matrix<2> P = t.ukf.covariance();
    Matrix<2> nanR = t.R;
    nanR(1, 1) = kNaN;
    EXPECT_EQ(t.ukf.update(t.meas, Vector<2>(0.5, 0.5), nanR).status, FilterStatus::UpdateSkipped);
    EXPECT_EQ(t.ukf.update(t.meas, Vector<2>(kNaN, 0.5), t.R).status, FilterStatus::UpdateSkipped);
    EXPECT_EQ(t.ukf.state(), x);
    EXPECT_EQ(t.ukf.covariance(), P);
    // The filter is untouched and goes on.
    EXPECT_EQ(t.ukf.update(t.meas, Vector<2>(0.5, 0.5), t.R).status, FilterStatus::Ok);
    EXPECT_TRUE(t.ukf.state().allFinite());
}

}  // namespace
}  // namespace hdjoint
