#include "compliance_model.h"

#include "hysteresis.h"
#include "transmission.h"

namespace hdjoint {

ComplianceModel::ComplianceModel(const Parameters& p) : p_(p), delay_(delay_samples(p)) {}

ComplianceSample ComplianceModel::step(double i_m, double theta_m, double theta_l) {
    ComplianceSample s;
    s.theta_m = theta_m;
    s.theta_l = theta_l;
    if (delay_ > 0) {
        const long index = static_cast<long>(received_);
        line_[2 * (index % kCapacity)] = theta_m;
        line_[2 * (index % kCapacity) + 1] = theta_l;
        received_ += 1.0;
        s.ready = index >= delay_;
        const long matched = s.ready ? index - delay_ : 0;  // before that: the first angles
        s.theta_m = line_[2 * (matched % kCapacity)];
        s.theta_l = line_[2 * (matched % kCapacity) + 1];
    }
    const ComplianceEstimate c = compliance_estimate(i_m, s.theta_m, s.theta_l, p_);
    s.dtheta_f = c.dtheta_f;
    s.valid = c.valid;
    s.tau = c.tau;
    s.torsion = c.dtheta_f;
    if (p_.hys_H > 0.0 && s.valid && s.ready) {
        // Driven by the eq. (4) torsion; the first sample starts from z = 0.
        if (samples_ > 0.0) z_ = dahl_update(z_, c.dtheta_f - previous_dtheta_f_, p_.hys_H, p_.hys_sigma);
        previous_dtheta_f_ = c.dtheta_f;
        s.z = z_;
        s.tau += z_;
    }
    // With hysteresis or backlash the torque is no longer eq. (5) of the
    // measured torsion: give the UKF the torsion eq. (5) maps to this torque.
    // (Skipped otherwise: the paper's model stays bit for bit.)
    if (s.valid && (p_.hys_H > 0.0 || p_.backlash > 0.0)) s.torsion = flexspline_torsion(s.tau, p_);
    if (s.valid && s.ready) samples_ += 1.0;
    return s;
}

// [z, previous dtheta_f, samples, received, then (theta_m, theta_l) of the
//  samples received - delay .. received - 1 (zeros before the first)]
void ComplianceModel::save(std::vector<double>* out) const {
    out->insert(out->end(), {z_, previous_dtheta_f_, samples_, received_});
    const long received = static_cast<long>(received_);
    for (long index = received - delay_; index < received; ++index) {
        const bool held = index >= 0;
        out->push_back(held ? line_[2 * (index % kCapacity)] : 0.0);
        out->push_back(held ? line_[2 * (index % kCapacity) + 1] : 0.0);
    }
}

bool ComplianceModel::load(const std::vector<double>& in, std::size_t* cursor) {
    const std::size_t size = 4 + 2 * static_cast<std::size_t>(delay_);
    if (in.size() < *cursor + size) return false;
    const double* d = in.data() + *cursor;
    if (!(d[3] >= 0.0) || d[3] != static_cast<double>(static_cast<long>(d[3]))) return false;
    z_ = d[0];
    previous_dtheta_f_ = d[1];
    samples_ = d[2];
    received_ = d[3];
    const long received = static_cast<long>(received_);
    line_.fill(0.0);
    for (long k = 0; k < delay_; ++k) {
        const long index = received - delay_ + k;
        if (index < 0) continue;
        line_[2 * (index % kCapacity)] = d[4 + 2 * k];
        line_[2 * (index % kCapacity) + 1] = d[5 + 2 * k];
    }
    *cursor += size;
    return true;
}

}  // namespace hdjoint
