#include "paper_ukf_models.h"

#include <cmath>

#include "transmission.h"

namespace hdjoint {

PaperSystemModel::PaperSystemModel(const Parameters& p, double Ts) {
    // omega' = (u - Bm*omega - tau_f/N)/Jm; with a = Bm/Jm the ZOH gain is
    // g = (1 - exp(-a*Ts))/a, which tends to Ts as Bm -> 0.
    const double a = p.Bm / p.Jm;
    const double g = a > 0.0 ? -std::expm1(-a * Ts) / a : Ts;
    F00 = std::exp(-a * Ts);
    F01 = -g / (p.N * p.Jm);
    B0 = g / p.Jm;
}

PaperMeasurementModel::Vector PaperMeasurementModel::h(const hdjoint::Vector<2>& x) const {
    Vector z;
    z << x(0), flexspline_torsion(x(1), Cf, Kf);
    return z;
}

}  // namespace hdjoint
