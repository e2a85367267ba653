#pragma once
// A fixed-size Unscented Kalman Filter, eq. (9)-(31), generic over its system
// and measurement models (types with f(x, u) and h(x)).
//
// Safeguards the paper leaves out: sigma points are redrawn from the
// predicted covariance before the update (eq. 22-24), covariances are kept
// symmetric, an indefinite covariance is repaired (or reset to the initial
// one) and reported as a status instead of aborting, and the gain comes from
// a solve, never an explicit inverse.
#include <limits>
#include <type_traits>

#include "sigma_points.h"

namespace hdjoint {

enum class FilterStatus {
    Ok,
    CovarianceRepaired,  // jitter was added to keep P positive definite
    CovarianceReset,     // P could not be factorised and was reset to P0
    UpdateSkipped,       // innovation covariance singular: measurement ignored
    SampleRejected,      // the innovation failed the outlier gate: measurement (or input) ignored
};

// What a system or measurement model may declare: kExtended (an analytic
// Jacobian), kLinear, kMovingStates (F's rows from it on are the identity's).
namespace model_traits {
template <class Model, template <class> class Member, class = void>
struct Declared : std::false_type {};
template <class Model, template <class> class Member>
struct Declared<Model, Member, std::void_t<Member<Model>>> : std::true_type {};
template <class Model, template <class> class Member>
constexpr bool declares = Declared<Model, Member>::value;
template <class M>
using ExtendedFlag = decltype(M::kExtended);
template <class M>
using LinearFlag = decltype(M::kLinear);
template <class M>
using MovingStates = decltype(M::kMovingStates);
}  // namespace model_traits

template <int NX>
class UnscentedKalmanFilter {
public:
    using State = Vector<NX>;
    using Covariance = Matrix<NX>;

    UnscentedKalmanFilter() = default;
    UnscentedKalmanFilter(const SigmaWeights<NX>& weights, const State& x0, const Covariance& P0)
        : weights_(weights), x_(x0), P_(P0), P0_(P0) {}

    const State& state() const { return x_; }
    const Covariance& covariance() const { return P_; }
    State& state() { return x_; }
    Covariance& covariance() { return P_; }
    const Covariance& initial_covariance() const { return P0_; }

    // eq. (16)-(21). A system model that declares itself linear (kLinear and
    // a transition() matrix) is propagated exactly as F P F^T + Q: for a
    // linear f that is what the unscented transform computes, without
    // 2n+1 model evaluations.
    //
    // A system model that declares kExtended (a near-linear model with an
    // analytic Jacobian: step(x, u, &F) gives the next state and the
    // transition Jacobian at x) is propagated as F P F^T + Q, the extended
    // filter's prediction; transition() then returns that F (an RTS
    // smoother needs it). One that also declares kMovingStates = m says
    // F's rows from m on are the identity's (constants and random walks):
    // the product then costs about half.
    template <class System>
    FilterStatus predict(const System& system, const typename System::Control& u, const Covariance& Q) {
        if constexpr (is_extended<System>()) {
            FilterStatus status = FilterStatus::Ok;
            if (!P_.allFinite() || !x_.allFinite()) {
                P_ = P0_;
                if (!x_.allFinite()) x_.setZero();
                status = FilterStatus::CovarianceReset;
            }
            x_ = system.step(x_, u, &F_);
            propagate<moving_states<System>()>(Q);
            return status;
        }
        if constexpr (is_linear<System>()) {
            FilterStatus status = FilterStatus::Ok;
            if (!P_.allFinite() || !x_.allFinite()) {
                P_ = P0_;
                if (!x_.allFinite()) x_.setZero();
                status = FilterStatus::CovarianceReset;
            }
            const Covariance F = system.transition();
            x_ = system.f(x_, u);
            P_ = F * P_ * F.transpose() + Q;
            symmetrize(&P_);
            return status;
        }
        SigmaPoints<NX> chi;
        const FilterStatus drawn = draw(&chi);
        for (int i = 0; i < chi.cols(); ++i) chi.col(i) = system.f(chi.col(i), u);
        unscented_transform<NX, 2 * NX + 1>(chi, weights_.mean, weights_.covariance, &x_, &P_);
        P_ += Q;
        symmetrize(&P_);
        return drawn;
    }

    // What an update saw: the innovation, its covariance and the normalised
    // innovation squared (NIS), which residual analysis needs.
    template <int NZ>
    struct Update {
        FilterStatus status = FilterStatus::Ok;
        Vector<NZ> innovation = Vector<NZ>::Zero();
        Matrix<NZ> innovation_covariance = Matrix<NZ>::Zero();
        double nis = 0.0;
    };

    // eq. (22)-(31). A measurement model that declares itself linear
    // (kLinear and a jacobian() matrix H) is updated exactly, with
    // Pzz = H P H^T + R and Pxz = P H^T: for a linear h that is what the
    // unscented transform computes, without drawing sigma points.
    // A finite `gate` rejects an innovation whose NIS exceeds it (linear
    // measurement models): the state is left as predicted, status SampleRejected.
    template <class Measurement>
    Update<Measurement::kSize> update(const Measurement& model, const typename Measurement::Vector& z,
                        const typename Measurement::Covariance& R,
                        double gate = std::numeric_limits<double>::infinity()) {
        constexpr int NZ = Measurement::kSize;
        Update<NZ> result;
        if constexpr (is_linear<Measurement>()) {
            if (!P_.allFinite() || !x_.allFinite()) {
                P_ = P0_;
                if (!x_.allFinite()) x_.setZero();
                result.status = FilterStatus::CovarianceReset;
            }
            const Eigen::Matrix<double, NZ, NX> H = model.jacobian();
            const Eigen::Matrix<double, NX, NZ> Pxz = P_ * H.transpose();
            Matrix<NZ> Pzz = H * Pxz + R;
            symmetrize(&Pzz);
            result.innovation = z - model.h(x_);
            result.innovation_covariance = Pzz;
            SpdSolver<NZ> solver;
            if (!solver.compute(Pzz) || !result.innovation.allFinite()) {
                result.status = FilterStatus::UpdateSkipped;
                return result;
            }
            result.nis = result.innovation.dot(solver.solve(result.innovation));
            if (!(result.nis <= gate)) {
                result.status = FilterStatus::SampleRejected;
                return result;
            }
            const Eigen::Matrix<double, NX, NZ> K =
                solver.solve(Eigen::Matrix<double, NZ, NX>(Pxz.transpose())).transpose();
            x_ += K * result.innovation;
            // Joseph-free form, K Pzz K^T = K Pxz^T: symmetric, so one
            // triangle is computed and mirrored.
            for (int j = 0; j < NX; ++j)
                for (int i = j; i < NX; ++i) P_(j, i) = P_(i, j) = 0.5 * (P_(i, j) + P_(j, i)) - K.row(i).dot(Pxz.row(j));
            return result;
        }
        SigmaPoints<NX> chi;
        result.status = draw(&chi);
        Eigen::Matrix<double, NZ, 2 * NX + 1> zeta;
        for (int i = 0; i < chi.cols(); ++i) zeta.col(i) = model.h(chi.col(i));
        Vector<NZ> z_hat;
        Matrix<NZ> Pzz;
        unscented_transform<NZ, 2 * NX + 1>(zeta, weights_.mean, weights_.covariance, &z_hat, &Pzz);
        Pzz += R;
        symmetrize(&Pzz);
        const Eigen::Matrix<double, NX, NZ> Pxz =
            (chi.colwise() - x_) * weights_.covariance.asDiagonal() * (zeta.colwise() - z_hat).transpose();
        result.innovation = z - z_hat;
        result.innovation_covariance = Pzz;
        SpdSolver<NZ> solver;
        if (!solver.compute(Pzz) || !result.innovation.allFinite()) {
            result.status = FilterStatus::UpdateSkipped;
            return result;
        }
        // K = Pxz Pzz^-1, taken as the transpose of Pzz^-1 Pxz^T.
        const Eigen::Matrix<double, NX, NZ> K = solver.solve(Eigen::Matrix<double, NZ, NX>(Pxz.transpose())).transpose();
        x_ += K * result.innovation;
        P_ -= K * Pzz * K.transpose();
        symmetrize(&P_);
        result.nis = result.innovation.dot(solver.solve(result.innovation));
        return result;
    }

    // The transition Jacobian of the last extended prediction.
    const Covariance& transition() const { return F_; }

private:
    // P = F P F^T + Q, F's rows from M on the identity's: with B = F_top P,
    // [B F_top^T, B_right; B_right^T, P_bottom-right].
    template <int M>
    void propagate(const Covariance& Q) {
        if constexpr (M >= NX) {
            Covariance FP;
            FP.noalias() = F_ * P_;
            P_ = Q;
            P_.noalias() += FP * F_.transpose();
        } else {
            const Eigen::Matrix<double, M, NX> B = F_.template topRows<M>() * P_;
            P_.template topLeftCorner<M, M>().noalias() = B * F_.template topRows<M>().transpose();
            P_.template topRightCorner<M, NX - M>() = B.template rightCols<NX - M>();
            P_.template bottomLeftCorner<NX - M, M>() = B.template rightCols<NX - M>().transpose();
            P_ += Q;
        }
        symmetrize(&P_);
    }
    // A model's optional declarations (model_traits), or their defaults.
    template <class System>
    static constexpr int moving_states() {
        if constexpr (model_traits::declares<System, model_traits::MovingStates>) return System::kMovingStates;
        else return NX;
    }
    template <class Model>
    static constexpr bool is_extended() {
        if constexpr (model_traits::declares<Model, model_traits::ExtendedFlag>) return Model::kExtended;
        else return false;
    }
    template <class Model>
    static constexpr bool is_linear() {
        if constexpr (model_traits::declares<Model, model_traits::LinearFlag>) return Model::kLinear;
        else return false;
    }

    // Sigma points from the current mean and covariance, repairing or
    // resetting P when it cannot be factorised.
    FilterStatus draw(SigmaPoints<NX>* chi) {
        Covariance L;
        FilterStatus status = FilterStatus::Ok;
        switch (robust_cholesky<NX>(&P_, &L)) {
            case FactorStatus::Ok: break;
            case FactorStatus::Repaired: status = FilterStatus::CovarianceRepaired; break;
            case FactorStatus::Failed:
                P_ = P0_;
                robust_cholesky<NX>(&P_, &L);
                if (!x_.allFinite()) x_.setZero();
                status = FilterStatus::CovarianceReset;
                break;
        }
        *chi = sigma_points<NX>(x_, L, weights_.gamma);
        return status;
    }

    SigmaWeights<NX> weights_;
    State x_ = State::Zero();
    Covariance P_ = Covariance::Identity();
    Covariance P0_ = Covariance::Identity();
    Covariance F_ = Covariance::Identity();
};

}  // namespace hdjoint
