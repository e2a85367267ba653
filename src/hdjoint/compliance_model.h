#pragma once
// The estimator's compliance model run sample by sample: eq. (3)-(8) of
// transmission.h plus the beyond-the-paper terms that carry state from one
// sample to the next -- Dahl hysteresis on the flexspline torsion (hys_H,
// hys_sigma) and the delay of the motor current behind the encoders
// (i_delay). The torque estimator and the batch path both run it.
#include <array>
#include <cstddef>
#include <vector>

#include "parameters.h"

namespace hdjoint {

struct ComplianceSample {
    bool ready = true;      // false while the delay line fills: no angles yet match this current
    bool valid = false;     // false: singular torsion, tau is meaningless
    double theta_m = 0.0;   // the encoder angles matched with this sample's current (delayed), rad
    double theta_l = 0.0;
    double dtheta_f = 0.0;  // eq. (4) torsion, rad
    double z = 0.0;         // hysteresis torque, N.m
    double tau = 0.0;       // eq. (8) torque (on the torsion beyond any backlash) + z, N.m
    double torsion = 0.0;   // the torsion the UKF measures: the one eq. (5) maps to tau, rad
};

class ComplianceModel {
public:
    explicit ComplianceModel(const Parameters& p);

    // One sample. The current is matched with the encoder angles of
    // delay_samples(p) samples before; until that many have arrived the
    // sample is not ready (its torque uses the first angles, and the
    // hysteresis does not move). A singular sample leaves the hysteresis as
    // it was (its angles still enter the delay line).
    ComplianceSample step(double i_m, double theta_m, double theta_l);

    // Flat state, appended to / read from a vector at *cursor: 4 values and
    // the angle pairs the delay line still needs.
    void save(std::vector<double>* out) const;
    bool load(const std::vector<double>& in, std::size_t* cursor);

private:
    static constexpr int kCapacity = kMaxDelaySamples + 1;
    Parameters p_;
    long delay_ = 0;                  // samples
    double z_ = 0.0;                  // Dahl hysteresis torque
    double previous_dtheta_f_ = 0.0;
    double samples_ = 0.0;            // valid, ready samples seen (counts kept as doubles for the flat state)
    double received_ = 0.0;           // samples that entered the delay line
    std::array<double, 2 * kCapacity> line_{};  // ring of (theta_m, theta_l), slot = sample index % kCapacity
};

}  // namespace hdjoint
