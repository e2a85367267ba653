#pragma once
// Van der Merwe's scaled sigma points, eq. (15)-(18): the weights and the
// 2n+1 points around a mean. A strategy of its own so the filter stays
// generic over how points are drawn.
#include "linear_algebra.h"

namespace hdjoint {

template <int N>
struct SigmaWeights {
    static constexpr int kCount = 2 * N + 1;
    Eigen::Matrix<double, kCount, 1> mean;
    Eigen::Matrix<double, kCount, 1> covariance;
    double gamma = 0.0;  // sqrt(n + lambda), eq. (17)
};

template <int N>
SigmaWeights<N> merwe_weights(double alpha, double beta, double kappa) {
    SigmaWeights<N> w;
    const double n = N;
    const double lambda = alpha * alpha * (n + kappa) - n;
    w.gamma = std::sqrt(n + lambda);
    w.mean.setConstant(1.0 / (2.0 * (n + lambda)));
    w.covariance = w.mean;
    w.mean(0) = lambda / (n + lambda);
    w.covariance(0) = lambda / (n + lambda) + 1.0 - alpha * alpha + beta;
    return w;
}

template <int N>
using SigmaPoints = Eigen::Matrix<double, N, 2 * N + 1>;

// eq. (16)-(18) from a mean and a lower Cholesky factor of the covariance.
template <int N>
SigmaPoints<N> sigma_points(const Vector<N>& x, const Matrix<N>& L, double gamma) {
    SigmaPoints<N> chi;
    chi.col(0) = x;
    for (int i = 0; i < N; ++i) {
        chi.col(1 + i) = x + gamma * L.col(i);
        chi.col(1 + N + i) = x - gamma * L.col(i);
    }
    return chi;
}

// The unscented transform, eq. (20)-(21) and (26)-(28): weighted mean and
// covariance of transformed points (a pure function; noise is added by the caller).
template <int M, int S>
void unscented_transform(const Eigen::Matrix<double, M, S>& points,
                         const Eigen::Matrix<double, S, 1>& wm,
                         const Eigen::Matrix<double, S, 1>& wc,
                         Vector<M>* mean, Matrix<M>* covariance) {
    *mean = points * wm;
    const Eigen::Matrix<double, M, S> deviation = points.colwise() - *mean;
    *covariance = deviation * wc.asDiagonal() * deviation.transpose();
}

}  // namespace hdjoint
