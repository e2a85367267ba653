#pragma once
// The paper's torque estimator: the compliance model of eq. (3)-(8) and the
// UKF of eq. (9)-(31), run at a fixed sample period on encoder angles and
// motor current; beside them the joint-state filter (tau_hat, beyond the paper).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "compliance_model.h"
#include "estimator_signals.def"
#include "joint_state_filter.h"
#include "paper_ukf_models.h"
#include "parameters.h"
#include "sample_clock.h"
#include "signal_table.h"
#include "ukf.h"

namespace hdjoint {

struct EstimatorInputs {
    HDJ_ESTIMATOR_SIGNALS(HDJ_MEMBER, HDJ_SKIP, HDJ_SKIP)
};

// The FMU's outputs, then the batch path's internal signals (nis, ...).
struct EstimatorOutputs {
    HDJ_ESTIMATOR_SIGNALS(HDJ_SKIP, HDJ_MEMBER, HDJ_MEMBER)
};

// The rows of estimator_signals.def (value references: see there).
const SignalTable<EstimatorInputs, EstimatorOutputs>& estimator_signals();

// How old (in samples) the inputs of a step may be and still count as a
// reading at a sample (advance_to). Measured by benchmarks/jitter_tolerance.py:
// with a reading used only at a step's first sample, 10-80 % jitter made
// tau_hat 18-40 % worse (a jittered row may hold two samples and the next
// none, so a reading is lost); a reading up to 1.5 samples old keeps it.
constexpr double kMaxReadingAge = 1.5;

// The gate on readings no sensor could produce (step): a current beyond
// kWildCurrentMultiple * i_peak (a current sensor's range is a small multiple
// of its amplifier's peak current), a non-finite value, or an encoder angle
// that moved further since the last accepted reading than the joint's
// largest speed allows: omega_m_max (omega_m_max/N for the link) times the
// time since then plus kMaxReadingAge samples (a late reading), plus
// kJumpCounts counts of the encoder (0 counts: no quantisation). Such a
// reading is treated as missing: both filters predict over it (status
// ReadingGated); the estimate never sees it.
// Once the filters run, a torsion no torque explains (|Cf*Kf*dtheta_f| >=
// pi/2) is gated the same way, until it has lasted kMaxSingularTime: then it
// is no glitch but the model (N, a0, Kf, Cf), and the estimator stops
// (SingularTorsion).
constexpr double kWildCurrentMultiple = 10.0;
constexpr double kJumpCounts = 2.0;
constexpr double kMaxSingularTime = 0.1;  // s

enum class EstimatorStatus {
    Ok,
    CovarianceRepaired,  // the UKF repaired an indefinite covariance (can go on)
    CovarianceReset,     // the UKF reset its covariance (can go on)
    UpdateSkipped,       // the measurement update was skipped (can go on)
    ReadingsHeld,        // a gap: a step held its inputs over several samples; the filters predicted over the later ones
    SampleRejected,      // the joint-state filter rejected an outlier sample and predicted over it (can go on)
    ReadingGated,        // a reading no sensor could produce (see kWildCurrentMultiple): both filters predicted over it
    SingularTorsion,     // |Cf*Kf*dtheta_f| >= pi/2: no torque explains the torsion
    InvalidInput,        // NaN or infinite input
    StepTooLong,         // a step would run more than SampleClock::kMaxSamplesPerStep samples
};

// True for statuses after which the estimate is still usable.
inline bool recoverable(EstimatorStatus s) {
    return s != EstimatorStatus::SingularTorsion && s != EstimatorStatus::InvalidInput &&
           s != EstimatorStatus::StepTooLong;
}

class TorqueEstimator {
public:
    // Samples fall at start_time + k*Ts.
    explicit TorqueEstimator(const Parameters& p, double start_time = 0.0);

    // The outputs before the first sample: the compliance model on the start
    // inputs (zero torque where the torsion is singular) and the initial deviations.
    void show_start(const EstimatorInputs& in);

    // Runs the samples due before `end` (see SampleClock) on the inputs `in`,
    // held, which were read at `read_at` (the step's start); `after_sample()`
    // is called after each. A sample takes the inputs as a reading while they
    // are less than kMaxReadingAge samples old (jitter: a reading a little
    // late is still the best one); a step that holds them longer (a gap in a
    // recording, a communication step longer than Ts) is predicted over by
    // both filters without readings (status ReadingsHeld; the deviations
    // widen), never fed the same angles as if the joint had stopped. Returns
    // the worst status (StepTooLong, with nothing run, beyond the step bound)
    // and the message of the first sample that was not Ok (of the failing
    // sample, when one fails).
    template <class AfterSample>
    EstimatorStatus advance_to(double end, double read_at, const EstimatorInputs& in, std::string* message,
                               AfterSample after_sample);
    EstimatorStatus advance_to(double end, double read_at, const EstimatorInputs& in,
                               std::string* message = nullptr) {
        return advance_to(end, read_at, in, message, [] {});
    }

    // Process one sample (inputs valid at this sample's time). `message`,
    // when given, names what went wrong for any status but Ok. With i_delay
    // the current is matched with the angles of round(i_delay/Ts) samples
    // before, and the first that many samples only fill the delay line.
    // With `reading` false the angles are not a new reading (held since the
    // last sample): the compliance model runs on them, the UKF and the
    // joint-state filter only predict (ReadingsHeld).
    // `age`: how long before this sample the inputs were read (s; a jittered row).
    EstimatorStatus step(const EstimatorInputs& in, std::string* message = nullptr, bool reading = true,
                         double age = 0.0);

    const EstimatorOutputs& outputs() const { return out_; }
    const Parameters& parameters() const { return p_; }
    long samples() const { return samples_; }
    // Readings gated so far (status ReadingGated).
    long readings_gated() const { return gated_; }
    // Eq. (11)'s input of the last sample: Kt*i_m (+ cogging) - tau_fm(omega_m, t).
    double ukf_input() const { return previous_u_; }

    // The state as named fields (parameters excluded; see state_fields.h),
    // and the same as a flat vector.
    std::vector<double> save_state() const { return save_fields(*this); }
    bool load_state(const std::vector<double>& data) { return load_fields(*this, data); }
    template <class Archive>
    bool fields(Archive& a);

    // The joint-state filter (tau_hat): its last sample, for the smoother.
    const JointStateFilter& joint_filter() const { return joint_; }

private:
    // Why `in` is a reading no sensor could produce (see kWildCurrentMultiple), or "".
    std::string wild(const EstimatorInputs& in) const;
    // One sample on readings that passed the gate (or, held, in their place).
    EstimatorStatus sample(const EstimatorInputs& in, std::string* message, bool reading, double age);
    long max_singular_samples() const { return static_cast<long>(std::ceil(kMaxSingularTime / p_.Ts)); }
    // A sample whose readings were held (see step): both filters predict.
    EstimatorStatus predict_held(const EstimatorInputs& in, const ComplianceSample& c, std::string* message);
    // Outputs that show the compliance model only (before the filters start).
    void show_compliance(double tau, double dtheta_f);
    // 6: samples_held; 7: the torque error e; 8: the filter's hysteresis; 9: the current sensor's gain; 10: the gate
    static constexpr long kStateVersion = 10;

    Parameters p_;
    PaperSystemModel system_;
    PaperMeasurementModel measurement_;
    Matrix<2> Q_ = Matrix<2>::Zero();
    Matrix<2> R_ = Matrix<2>::Zero();
    UnscentedKalmanFilter<2> ukf_;
    ComplianceModel compliance_;
    JointStateFilter joint_;
    EstimatorOutputs out_;
    double previous_theta_m_ = 0.0;
    double previous_u_ = 0.0;  // Kt*i_m - tau_fm of the previous sample
    // Running means of NIS/2 of the paper UKF and the joint-state filter (std_nis_time).
    double nis_mean_ukf_ = 1.0, nis_mean_hat_ = 1.0;
    long samples_ = 0;
    long samples_held_ = 0;  // samples predicted without a reading since the last reading (the UKF's speed spans them)
    // The gate: the last accepted reading, the samples since it, the readings gated.
    EstimatorInputs accepted_{};
    bool has_accepted_ = false;
    long since_accepted_ = 0;
    long gated_ = 0;
    long singular_run_ = 0;  // samples in a row whose torsion no torque explained
    long gated_run_ = 0;     // readings in a row gated (the first is said, the others counted)
    SampleClock clock_;
};

template <class AfterSample>
EstimatorStatus TorqueEstimator::advance_to(double end, double read_at, const EstimatorInputs& in,
                                            std::string* message, AfterSample after_sample) {
    EstimatorStatus worst = EstimatorStatus::Ok;
    std::string first;
    bool first_sample = true;
    const bool bounded = clock_.run_until(end, [&](double t) {
        std::string m;
        // Within the sample clock's tolerance (a millionth of Ts) a reading is on time.
        const double age = t - read_at > 1e-6 * p_.Ts ? t - read_at : 0.0;
        const EstimatorStatus s = step(in, &m, first_sample || age < kMaxReadingAge * p_.Ts, age);
        first_sample = false;
        if (s != EstimatorStatus::Ok && first.empty()) first = m;
        worst = std::max(worst, s);
        if (!recoverable(s)) {
            first = m;  // the failure's own message, not an earlier sample's warning
            return false;
        }
        after_sample();
        return true;
    }, &first);
    if (!bounded && worst == EstimatorStatus::Ok) worst = EstimatorStatus::StepTooLong;
    if (message) *message = first;
    return worst;
}

template <class Archive>
bool TorqueEstimator::fields(Archive& a) {
    long version = kStateVersion;  // a counter: checked in every reading
    return a("estimator_state_version", version, kStateVersion, kStateVersion) && a("ukf_state", ukf_.state()) &&
           a("ukf_covariance", ukf_.covariance()) && a("previous_theta_m", previous_theta_m_) &&
           a("previous_u", previous_u_) && a("nis_mean_ukf", nis_mean_ukf_) && a("nis_mean_hat", nis_mean_hat_) &&
           a("samples_held", samples_held_) && a("gate_has_reading", has_accepted_) &&
           a("gate_i_m", accepted_.i_m) && a("gate_theta_m", accepted_.theta_m) &&
           a("gate_theta_l", accepted_.theta_l) && a("gate_samples_since", since_accepted_) &&
           a("readings_gated", gated_) && a("singular_run", singular_run_) &&
           a("gated_run", gated_run_) &&
           output_fields(a, estimator_signals(), out_) &&
           a.part("compliance_model", compliance_) && a.part("joint_state_filter", joint_) &&
           a("samples", samples_) && clock_.fields(a);
}

}  // namespace hdjoint
