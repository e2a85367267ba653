#include "compliance_model.h"

#include "hysteresis.h"
#include "transmission.h"

namespace hdjoint {

ComplianceSample ComplianceModel::step(double i_m, double theta_m, double theta_l) {
    const ComplianceEstimate c = compliance_estimate(i_m, theta_m, theta_l, p_);
    ComplianceSample s;
    s.dtheta_f = c.dtheta_f;
    s.valid = c.valid;
    s.tau = c.tau;
    s.torsion = c.dtheta_f;
    if (p_.hys_H > 0.0 && s.valid) {
        // Driven by the eq. (4) torsion; the first sample starts from z = 0.
        // A singular sample is left out (as the estimator leaves it out).
        if (samples_ > 0.0) z_ = dahl_update(z_, c.dtheta_f - previous_dtheta_f_, p_.hys_H, p_.hys_sigma);
        previous_dtheta_f_ = c.dtheta_f;
        s.z = z_;
        s.tau += z_;
    }
    // With hysteresis or backlash the torque is no longer eq. (5) of the
    // measured torsion: give the UKF the torsion eq. (5) maps to this torque.
    // (Skipped otherwise: the paper's model stays bit for bit.)
    if (s.valid && (p_.hys_H > 0.0 || p_.backlash > 0.0)) s.torsion = flexspline_torsion(s.tau, p_);
    if (s.valid) samples_ += 1.0;
    return s;
}

void ComplianceModel::save(std::vector<double>* out) const {
    out->insert(out->end(), {z_, previous_dtheta_f_, samples_});
}

bool ComplianceModel::load(const std::vector<double>& in, std::size_t* cursor) {
    if (in.size() < *cursor + kStateSize) return false;
    z_ = in[(*cursor)++];
    previous_dtheta_f_ = in[(*cursor)++];
    samples_ = in[(*cursor)++];
    return true;
}

}  // namespace hdjoint
