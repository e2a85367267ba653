#pragma once
// Motor-side friction of eq. (2): tau_fm (Coulomb, smoothed so the model stays
// differentiable through zero speed) plus viscous Bm*omega_m.
#include <cmath>

#include "parameters.h"

namespace hdjoint {

inline double coulomb_friction(double omega_m, const Parameters& p) {
    return p.Fc * std::tanh(omega_m / p.omega_fc);
}

inline double motor_friction(double omega_m, const Parameters& p) {
    return coulomb_friction(omega_m, p) + p.Bm * omega_m;
}

}  // namespace hdjoint
