#pragma once
// Dahl hysteresis (beyond the paper): a torque z that follows the torsion x
// with dz/dx = sigma*(1 - z/H*sign(dx)), saturating at +-H. Rate-independent,
// so a sampled estimator can update it exactly from torsion increments.
#include <cmath>

namespace hdjoint {

// z after a torsion increment dx: the exact solution of the Dahl law over
// a monotone increment, z -> s*H - (s*H - z)*exp(-sigma*|dx|/H), s = sign(dx).
// Unchanged for dx = 0 or H <= 0 (off).
inline double dahl_update(double z, double dx, double H, double sigma) {
    if (dx == 0.0 || !(H > 0.0)) return z;
    const double target = dx > 0.0 ? H : -H;
    return target - (target - z) * std::exp(-sigma * std::fabs(dx) / H);
}

}  // namespace hdjoint
