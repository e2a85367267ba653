#pragma once
// The estimator's compliance model run sample by sample: eq. (3)-(8) of
// transmission.h plus the beyond-the-paper terms that carry state from one
// sample to the next -- Dahl hysteresis on the flexspline torsion (hys_H,
// hys_sigma). The torque estimator and the batch path both run it.
#include <cstddef>
#include <vector>

#include "parameters.h"

namespace hdjoint {

struct ComplianceSample {
    bool valid = false;     // false: singular torsion, tau is meaningless
    double dtheta_f = 0.0;  // eq. (4) torsion, rad
    double z = 0.0;         // hysteresis torque, N.m
    double tau = 0.0;       // eq. (8) torque (on the torsion beyond any backlash) + z, N.m
    double torsion = 0.0;   // the torsion the UKF measures: the one eq. (5) maps to tau, rad
};

class ComplianceModel {
public:
    explicit ComplianceModel(const Parameters& p) : p_(p) {}

    // One sample. A singular one (valid = false) leaves the state as it was.
    ComplianceSample step(double i_m, double theta_m, double theta_l);

    // Flat state, appended to / read from a vector at *cursor.
    void save(std::vector<double>* out) const;
    bool load(const std::vector<double>& in, std::size_t* cursor);
    static constexpr std::size_t kStateSize = 3;

private:
    Parameters p_;
    double z_ = 0.0;                // Dahl hysteresis torque
    double previous_dtheta_f_ = 0.0;
    double samples_ = 0.0;          // valid samples seen (a count, kept as a double for the flat state)
};

}  // namespace hdjoint
