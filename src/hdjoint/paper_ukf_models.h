#pragma once
// The paper's UKF models, eq. (11)-(12): state [omega_m, tau_f], measurement
// [omega_m, dtheta_f], input u = Kt*i_m - tau_fm.
#include "linear_algebra.h"
#include "parameters.h"

namespace hdjoint {

// eq. (11): x_k = F x_{k-1} + B u_{k-1}, the exact zero-order-hold
// discretisation of eq. (2) with tau_f held (a random walk).
struct PaperSystemModel {
    using State = Vector<2>;
    using Control = double;
    static constexpr bool kLinear = true;  // the UKF may propagate it exactly
    double F00 = 1.0, F01 = 0.0, B0 = 0.0;

    PaperSystemModel() = default;
    PaperSystemModel(const Parameters& p, double Ts);

    State f(const State& x, Control u) const {
        State next;
        next << F00 * x(0) + F01 * x(1) + B0 * u, x(1);
        return next;
    }
    Matrix<2> transition() const {
        Matrix<2> F;
        F << F00, F01, 0.0, 1.0;
        return F;
    }
};

// eq. (12): the encoder-differenced speed and the flexspline torsion of eq. (5).
struct PaperMeasurementModel {
    static constexpr int kSize = 2;
    using Vector = hdjoint::Vector<2>;
    using Covariance = Matrix<2>;
    double Cf = 0.0, Kf = 1.0;

    PaperMeasurementModel() = default;
    explicit PaperMeasurementModel(const Parameters& p) : Cf(p.Cf), Kf(p.Kf) {}

    Vector h(const hdjoint::Vector<2>& x) const;
};

}  // namespace hdjoint
