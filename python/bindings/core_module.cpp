// hdjoint._core: the batch path to the C++ core, for work that runs the model
// many times (estimation over recordings, diagnosis). Same code as the FMUs.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/map.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "hdjoint/compliance_model.h"
#include "hdjoint/friction.h"
#include "hdjoint/hysteresis.h"
#include "hdjoint/joint_controller.h"
#include "hdjoint/joint_plant.h"
#include "hdjoint/joint_state_filter.h"
#include "hdjoint/parameters.h"
#include "hdjoint/torque_estimator.h"
#include "hdjoint/transmission.h"

namespace nb = nanobind;
using namespace hdjoint;

namespace {

using Array = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using OutArray = nb::ndarray<nb::numpy, double, nb::ndim<1>>;

// A parameter set from a dict of name -> value; unknown names are errors.
Parameters parameters_from(const std::map<std::string, double>& values, bool estimator, bool plant) {
    Parameters p;
    for (const auto& [name, value] : values) {
        const auto index = find_parameter(name);
        if (!index) throw std::invalid_argument("unknown parameter '" + name + "'");
        p.*(parameter_table()[*index].member) = value;
    }
    if (auto problem = validate(p, estimator, plant)) throw std::invalid_argument(*problem);
    return p;
}

// validate() on a whole set (both FMUs' parameters): the problem, or None.
std::optional<std::string> check_parameters(const std::map<std::string, double>& values) {
    try {
        parameters_from(values, true, true);
    } catch (const std::invalid_argument& e) {
        return std::string(e.what());
    }
    return std::nullopt;
}

OutArray make_array(std::vector<double>&& data) {
    auto* owned = new std::vector<double>(std::move(data));
    nb::capsule owner(owned, [](void* v) noexcept { delete static_cast<std::vector<double>*>(v); });
    return OutArray(owned->data(), {owned->size()}, owner);
}

void check_lengths(std::size_t n, std::initializer_list<std::size_t> sizes) {
    for (std::size_t s : sizes)
        if (s != n) throw std::invalid_argument("input arrays must all have the same length");
    if (n < 1) throw std::invalid_argument("input arrays are empty");
}

template <class In, class Out>
std::size_t signal_index(const SignalTable<In, Out>& table, const std::string& name) {
    for (std::size_t c = 0; c < table.size(); ++c)
        if (name == table[c].name) return c;
    throw std::logic_error("no signal " + name);
}

using OutTable = nb::ndarray<nb::numpy, double, nb::ndim<2>>;

OutTable make_table(std::vector<double>&& data, std::size_t columns) {
    auto* owned = new std::vector<double>(std::move(data));
    nb::capsule owner(owned, [](void* v) noexcept { delete static_cast<std::vector<double>*>(v); });
    return OutTable(owned->data(), {owned->size() / columns, columns}, owner);
}

// The estimator over a recording, with the FMU's timing: row j is a
// communication point; its step [t_j, t_j+1) runs the samples start + k*Ts
// inside it on row j's inputs, and row j's outputs are those after the step.
// The rows may come in blocks (the estimator carries over): a block's last
// row steps to `end` (the next block's first time; a recording's last row
// steps by Ts). With `keep_records`, the joint-state filter's samples are
// kept for the RTS smoother, and each row is given the index of the last
// sample its step ran (-1 before the filter starts).
class EstimatorRows {
public:
    EstimatorRows(const Parameters& p, double start_time, bool keep_records)
        : p_(p), estimator_(p, start_time), keep_records_(keep_records) {}

    struct Columns {
        std::vector<std::vector<double>> signals;  // one per signal of estimator_signals.def (inputs left empty)
        std::vector<double> status, last_record;
    };

    // `keep(record)` takes each kept filter sample as it comes.
    template <class Keep>
    Columns run(Array time, Array i_m, Array theta_m, Array theta_l, double end, Keep keep) {
        const std::size_t n = time.shape(0);
        check_lengths(n, {i_m.shape(0), theta_m.shape(0), theta_l.shape(0)});
        const auto& signals = estimator_signals();
        Columns c;
        c.signals.resize(signals.size());
        for (std::size_t k = 0; k < signals.size(); ++k)
            if (signals[k].kind != SignalKind::Input) c.signals[k].resize(n);
        c.status.resize(n);
        if (keep_records_) c.last_record.resize(n);
        nb::gil_scoped_release release;
        for (std::size_t j = 0; j < n; ++j, ++rows_) {
            const double step_end = j + 1 < n ? time(j + 1) : end;
            std::string message;
            const EstimatorStatus s = estimator_.advance_to(step_end, time(j), {i_m(j), theta_m(j), theta_l(j)}, &message, [&] {
                const JointStateFilter& filter = estimator_.joint_filter();
                if (keep_records_ && filter.started() && (records_ == 0 || filter.record().predicted)) {
                    keep(filter.record());
                    ++records_;
                }
            });
            if (!recoverable(s)) {
                nb::gil_scoped_acquire acquire;
                throw std::runtime_error("row " + std::to_string(rows_) + " (time " + std::to_string(time(j)) +
                                         " s): " + message);
            }
            if (keep_records_) c.last_record[j] = static_cast<double>(records_) - 1.0;
            for (std::size_t k = 0; k < signals.size(); ++k)
                if (signals[k].kind != SignalKind::Input) c.signals[k][j] = estimator_.outputs().*(signals[k].output);
            c.status[j] = static_cast<double>(s);
        }
        return c;
    }

    // The columns as named arrays: every output and internal signal, status (and last_record).
    static std::map<std::string, OutArray> named(Columns&& c) {
        const auto& signals = estimator_signals();
        std::map<std::string, OutArray> out;
        for (std::size_t k = 0; k < signals.size(); ++k)
            if (signals[k].kind != SignalKind::Input) out.emplace(signals[k].name, make_array(std::move(c.signals[k])));
        out.emplace("status", make_array(std::move(c.status)));
        if (!c.last_record.empty()) out.emplace("last_record", make_array(std::move(c.last_record)));
        return out;
    }

    const Parameters& parameters() const { return p_; }

private:
    Parameters p_;
    TorqueEstimator estimator_;
    bool keep_records_;
    long rows_ = 0, records_ = 0;
};

// The whole recording at once; with `smooth`, the RTS smoother in memory:
// row j gets the smoothed torque of the last sample its step ran (the
// causal tau_hat before the filter starts).
std::map<std::string, OutArray> run_estimator(const std::map<std::string, double>& values, Array time, Array i_m,
                                              Array theta_m, Array theta_l, bool smooth) {
    const Parameters p = parameters_from(values, true, false);
    check_lengths(time.shape(0), {});
    EstimatorRows rows(p, time(0), smooth);
    std::vector<JointFilterRecord> records;
    if (smooth) records.reserve(time.shape(0));
    EstimatorRows::Columns c = rows.run(time, i_m, theta_m, theta_l, time(time.shape(0) - 1) + p.Ts,
                                        [&records](const JointFilterRecord& r) { records.push_back(r); });
    std::map<std::string, OutArray> out;
    if (smooth) {
        const SmoothedTorque sm = smooth_joint_states(records, p);
        const auto& signals = estimator_signals();
        const std::vector<double>& tau_hat = c.signals[signal_index(signals, "tau_hat")];
        const std::vector<double>& std_hat = c.signals[signal_index(signals, "tau_hat_std")];
        const std::size_t n = tau_hat.size();
        std::vector<double> tau_s(n), std_s(n);
        for (std::size_t j = 0; j < n; ++j) {
            const long r = static_cast<long>(c.last_record[j]);
            tau_s[j] = r >= 0 ? sm.tau[static_cast<std::size_t>(r)] : tau_hat[j];
            std_s[j] = r >= 0 ? sm.tau_std[static_cast<std::size_t>(r)] : std_hat[j];
        }
        c.last_record.clear();
        out.emplace("tau_smooth", make_array(std::move(tau_s)));
        out.emplace("tau_smooth_std", make_array(std::move(std_s)));
    }
    out.merge(EstimatorRows::named(std::move(c)));
    return out;
}

// The estimator a block of rows at a time (a recording too long to hold):
// the same numbers as run_estimator on the whole. With keep_records, each
// block also returns the joint-state filter's new samples as a table of
// flat records (kRecordValues columns) for RtsSmoother, and each row the
// index of the last sample its step ran.
class EstimatorStream {
public:
    EstimatorStream(const std::map<std::string, double>& values, double start_time, bool keep_records)
        : rows_(parameters_from(values, true, false), start_time, keep_records), keep_records_(keep_records) {}

    std::map<std::string, nb::object> run(Array time, Array i_m, Array theta_m, Array theta_l, double end) {
        std::vector<double> flat;  // the records, flattened as they come (about one a row)
        if (keep_records_) flat.reserve(time.shape(0) * kRecordValues);
        auto keep = [&flat](const JointFilterRecord& r) {
            flat.resize(flat.size() + kRecordValues);
            flatten_record(r, flat.data() + flat.size() - kRecordValues);
        };
        std::map<std::string, nb::object> out;
        for (auto& [name, array] : EstimatorRows::named(rows_.run(time, i_m, theta_m, theta_l, end, keep)))
            out.emplace(name, nb::cast(array));
        if (keep_records_) out.emplace("records", nb::cast(make_table(std::move(flat), kRecordValues)));
        return out;
    }

private:
    EstimatorRows rows_;
    bool keep_records_;
};

// The RTS smoother's backward pass over flat records given in blocks, the
// last block first (each block in forward order): the smoothed torque and
// its deviation of each record of the block.
class RtsSmoother {
public:
    explicit RtsSmoother(const std::map<std::string, double>& values)
        : backward_(parameters_from(values, true, false)) {}

    std::map<std::string, OutArray> run(nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu> records) {
        if (records.shape(1) != kRecordValues)
            throw std::invalid_argument("records must have " + std::to_string(kRecordValues) + " columns");
        const std::size_t n = records.shape(0);
        std::vector<double> tau(n), tau_std(n);
        {
            nb::gil_scoped_release release;
            for (std::size_t j = n; j-- > 0;) {
                const RtsBackward::Torque t = backward_.step(unflatten_record(records.data() + j * kRecordValues));
                tau[j] = t.tau;
                tau_std[j] = t.tau_std;
            }
        }
        std::map<std::string, OutArray> out;
        out.emplace("tau_smooth", make_array(std::move(tau)));
        out.emplace("tau_smooth_std", make_array(std::move(tau_std)));
        return out;
    }

private:
    RtsBackward backward_;
};

// Samples below which a run is not worth a thread (starting one costs tens of microseconds).
constexpr std::size_t kSamplesPerThread = 4096;

// The estimator's compliance model, eq. (3)-(8) with the beyond-paper terms,
// run sample by sample (hysteresis and the current delay carry state; one
// row is one estimator sample). NaN where the torsion is singular. Without
// either, each sample stands alone: the run is split over up to `threads`
// threads, each with its own model, which computes the very same numbers.
std::map<std::string, OutArray> compliance(const std::map<std::string, double>& values, Array i_m, Array theta_m,
                                           Array theta_l, int threads) {
    const std::size_t n = i_m.shape(0);
    check_lengths(n, {theta_m.shape(0), theta_l.shape(0)});
    const Parameters p = parameters_from(values, true, false);
    std::vector<double> tau(n), dtheta_f(n), z(n);
    auto run = [&](ComplianceModel model, std::size_t begin, std::size_t end) {
        for (std::size_t j = begin; j < end; ++j) {
            const ComplianceSample c = model.step(i_m(j), theta_m(j), theta_l(j));
            tau[j] = c.valid ? c.tau : std::nan("");
            dtheta_f[j] = c.dtheta_f;
            z[j] = c.z;
        }
    };
    const ComplianceModel model(p);
    const bool stateless = !(p.hys_H > 0.0) && delay_samples(p) == 0;
    const std::size_t pieces =
        stateless ? std::clamp<std::size_t>(n / kSamplesPerThread, 1, static_cast<std::size_t>(std::max(threads, 1)))
                  : 1;
    if (pieces == 1) {
        run(model, 0, n);
    } else {
        nb::gil_scoped_release release;
        std::vector<std::thread> others;
        for (std::size_t k = 1; k < pieces; ++k) others.emplace_back(run, model, n * k / pieces, n * (k + 1) / pieces);
        run(model, 0, n / pieces);
        for (std::thread& other : others) other.join();
    }
    std::map<std::string, OutArray> out;
    out.emplace("tau_compliance", make_array(std::move(tau)));
    out.emplace("dtheta_f", make_array(std::move(dtheta_f)));
    out.emplace("hysteresis_torque", make_array(std::move(z)));
    return out;
}

// The Dahl hysteresis torque over a torsion sequence x, from z = 0 at x[0],
// by the model's exact update (for hysteresis regressors).
OutArray dahl(Array x, double H, double sigma) {
    if (!(H >= 0.0) || !std::isfinite(H)) throw std::invalid_argument("dahl: H must be finite and >= 0");
    if (!(sigma > 0.0) || !std::isfinite(sigma)) throw std::invalid_argument("dahl: sigma must be finite and > 0");
    const std::size_t n = x.shape(0);
    std::vector<double> z(n, 0.0);
    for (std::size_t j = 1; j < n; ++j) z[j] = dahl_update(z[j - 1], x(j) - x(j - 1), H, sigma);
    return make_array(std::move(z));
}

// The joint, open loop: inputs held over [t_j, t_j+1); outputs at every t_j
// (row 0 is the initial equilibrium).
std::map<std::string, OutArray> simulate_joint(const std::map<std::string, double>& values, Array time, Array i_m,
                                               Array tau_ext) {
    const std::size_t n = time.shape(0);
    check_lengths(n, {i_m.shape(0), tau_ext.shape(0)});
    const Parameters p = parameters_from(values, false, true);
    JointPlant plant(p);
    std::string message;
    if (!plant.initialize(tau_ext(0), &message)) throw std::runtime_error(message);
    std::vector<double> theta_m(n), theta_l(n), tau(n), omega_m(n), omega_l(n);
    std::vector<double> friction(n), cogging(n), link_friction(n), z_hys(n), elastic(n), scale(n);
    {
        nb::gil_scoped_release release;
        for (std::size_t j = 0; j < n; ++j) {
            if (j > 0 && !plant.advance(time(j) - time(j - 1), {i_m(j - 1), tau_ext(j - 1)}, &message)) {
                nb::gil_scoped_acquire acquire;
                throw std::runtime_error("row " + std::to_string(j) + ": " + message);
            }
            const PlantOutputs o = plant.outputs();
            theta_m[j] = o.theta_m;
            theta_l[j] = o.theta_l;
            tau[j] = o.tau_joint;
            omega_m[j] = o.omega_m;
            omega_l[j] = o.omega_link;
            const PlantInternals r = plant.internals();
            friction[j] = r.tau_friction;
            cogging[j] = r.tau_cogging;
            link_friction[j] = r.tau_link_friction;
            z_hys[j] = r.z_dahl + r.z_bouc_wen;
            elastic[j] = r.elastic_torsion;
            scale[j] = r.friction_scale;
        }
    }
    std::map<std::string, OutArray> out;
    out.emplace("theta_m", make_array(std::move(theta_m)));
    out.emplace("theta_l", make_array(std::move(theta_l)));
    out.emplace("tau_joint", make_array(std::move(tau)));
    out.emplace("omega_m", make_array(std::move(omega_m)));
    out.emplace("omega_link", make_array(std::move(omega_l)));
    out.emplace("tau_friction", make_array(std::move(friction)));
    out.emplace("tau_cogging", make_array(std::move(cogging)));
    out.emplace("tau_link_friction", make_array(std::move(link_friction)));
    out.emplace("z_hysteresis", make_array(std::move(z_hys)));
    out.emplace("elastic_torsion", make_array(std::move(elastic)));
    out.emplace("friction_scale", make_array(std::move(scale)));
    return out;
}

// Seconds for n samples of `step(theta_m, theta_l, i_m, t)` on a synthetic
// moving joint (0.5 rad link swing, 3 N.m torque), timed in C++: the cost
// per step without Python in the loop, for the benchmark script.
template <typename Step>
double time_on_moving_joint(const Parameters& p, long n, Step step) {
    double sink = 0.0;
    nb::gil_scoped_release release;
    const auto start = std::chrono::steady_clock::now();
    for (long k = 0; k < n; ++k) {
        const double t = static_cast<double>(k) * p.Ts;
        const double theta_l = 0.5 * std::sin(1.5 * t);
        const double tau = 3.0 * std::sin(1.5 * t);
        sink += step(p.N * (theta_l + tau / p.Kf), theta_l, tau / (p.N * p.Kt), t);
    }
    const auto stop = std::chrono::steady_clock::now();
    if (!std::isfinite(sink)) throw std::runtime_error("benchmark diverged");
    return std::chrono::duration<double>(stop - start).count();
}

// The whole estimator step (compliance model, paper UKF, joint-state filter).
double time_estimator(const std::map<std::string, double>& values, long n) {
    const Parameters p = parameters_from(values, true, false);
    TorqueEstimator estimator(p);
    return time_on_moving_joint(p, n, [&](double theta_m, double theta_l, double i_m, double) {
        estimator.step(EstimatorInputs{i_m, theta_m, theta_l});
        return estimator.outputs().tau_ukf;
    });
}

// The joint-state filter alone (tau_hat).
double time_joint_filter(const std::map<std::string, double>& values, long n) {
    const Parameters p = parameters_from(values, true, false);
    JointStateFilter filter(p);
    return time_on_moving_joint(p, n, [&](double theta_m, double theta_l, double i_m, double t) {
        filter.step(theta_m, theta_l, {i_m, 0.0, t});
        return filter.output().tau;
    });
}

// ---- the laws the diagnosis evaluates on recordings: the FMUs' own code ----

// Motor friction of eq. (2) at t seconds into a run: friction.h's law with
// the drift hypothesis friction_drift_scale (held at >= 0).
OutArray motor_friction_law(const std::map<std::string, double>& values, Array omega_m, Array t) {
    const std::size_t n = omega_m.shape(0);
    check_lengths(n, {t.shape(0)});
    const Parameters p = parameters_from(values, true, true);
    std::vector<double> f(n);
    for (std::size_t j = 0; j < n; ++j) f[j] = motor_friction(omega_m(j), p, friction_drift_scale(t(j), p));
    return make_array(std::move(f));
}

// The torque constant's warm-up scale Kt(t)/Kt at each time since the start of the run.
OutArray torque_constant_scale_law(const std::map<std::string, double>& values, Array t) {
    const std::size_t n = t.shape(0);
    check_lengths(n, {});
    const Parameters p = parameters_from(values, true, true);
    std::vector<double> s(n);
    for (std::size_t j = 0; j < n; ++j) s[j] = torque_constant_scale(t(j), p);
    return make_array(std::move(s));
}

// The kinematic error of eq. (7) with its extra orders at each pair of angles: the
// transmission's law (linear in its amplitudes, which the diagnosis uses as a basis).
OutArray kinematic_error_law(const std::map<std::string, double>& values, Array theta_m, Array theta_l) {
    const std::size_t n = theta_m.shape(0);
    check_lengths(n, {theta_l.shape(0)});
    const Parameters p = parameters_from(values, true, true);
    std::vector<double> e(n);
    for (std::size_t j = 0; j < n; ++j) e[j] = kinematic_error(theta_m(j), theta_l(j), p);
    return make_array(std::move(e));
}

// Cogging torque on the motor (0 when off).
OutArray cogging_law(const std::map<std::string, double>& values, Array theta_m) {
    const std::size_t n = theta_m.shape(0);
    check_lengths(n, {});
    const Parameters p = parameters_from(values, true, true);
    std::vector<double> c(n, 0.0);
    if (cogging_on(p))
        for (std::size_t j = 0; j < n; ++j) c[j] = cogging_torque(theta_m(j), p);
    return make_array(std::move(c));
}

// The torque the link's own dynamics need (the joint's link equation with no
// external torque, solved for the transmitted torque).
OutArray link_torque_law(const std::map<std::string, double>& values, Array theta_l, Array omega_l, Array alpha_l) {
    const std::size_t n = theta_l.shape(0);
    check_lengths(n, {omega_l.shape(0), alpha_l.shape(0)});
    const Parameters p = parameters_from(values, false, true);
    std::vector<double> tau(n);
    for (std::size_t j = 0; j < n; ++j) tau[j] = link_torque_needed(theta_l(j), omega_l(j), alpha_l(j), p);
    return make_array(std::move(tau));
}

ControllerParameters controller_parameters_from(const std::map<std::string, double>& values) {
    ControllerParameters p;
    for (const auto& [name, value] : values) {
        const ControllerParameterInfo* row = nullptr;
        for (std::size_t i = 0; i < controller_parameter_count() && !row; ++i)
            if (name == controller_parameter_table()[i].name) row = &controller_parameter_table()[i];
        if (!row) throw std::invalid_argument("unknown controller parameter '" + name + "'");
        p.*(row->member) = value;
    }
    if (auto problem = validate(p)) throw std::invalid_argument(*problem);
    return p;
}

// Each FMU's inputs, outputs and (batch-only) internal signals, from its signal table.
template <class In, class Out>
nb::list signal_rows(const SignalTable<In, Out>& table) {
    nb::list rows;
    for (const Signal<In, Out>& s : table) {
        nb::dict row;
        row["name"] = s.name;
        row["kind"] = s.kind == SignalKind::Input ? "input" : s.kind == SignalKind::Output ? "output" : "internal";
        row["unit"] = s.unit;
        row["description"] = s.description;
        rows.append(row);
    }
    return rows;
}

nb::dict fmu_signals() {
    nb::dict d;
    d["JointTorqueEstimator"] = signal_rows(estimator_signals());
    d["HarmonicDriveJoint"] = signal_rows(plant_signals());
    d["JointController"] = signal_rows(controller_signals());
    return d;
}

nb::list table() {
    nb::list rows;
    for (std::size_t i = 0; i < parameter_count(); ++i) {
        const ParameterInfo& p = parameter_table()[i];
        nb::dict row;
        row["name"] = p.name;
        row["unit"] = p.unit;
        row["default"] = p.default_value;
        row["min"] = p.min;
        row["max"] = p.max;
        row["scope"] = p.scope == Scope::Shared ? "shared" : p.scope == Scope::Plant ? "plant" : "estimator";
        row["description"] = p.description;
        row["value_reference"] = i;
        // The calibration prior (parameter_tolerance.def), NaN when never calibrated.
        const ToleranceInfo* tol = find_tolerance(p.name);
        row["tolerance_relative"] = tol ? tol->relative : std::nan("");
        row["tolerance_absolute"] = tol ? tol->absolute : std::nan("");
        row["tolerance_source"] = tol ? tol->source : "";
        rows.append(row);
    }
    return rows;
}

}  // namespace

NB_MODULE(_core, m) {
    m.doc() = "hdjoint C++ core: the batch path (same code as the FMUs)";
    // The batch status column's value for a sample the joint-state filter rejected as an outlier.
    m.attr("STATUS_SAMPLE_REJECTED") = static_cast<int>(EstimatorStatus::SampleRejected);
    // ... and for a sample without a new reading (a gap: its step held the inputs), predicted over.
    m.attr("STATUS_READINGS_HELD") = static_cast<int>(EstimatorStatus::ReadingsHeld);
    // ... and for a reading no sensor could produce (a wild value), treated as missing and predicted over.
    m.attr("STATUS_READING_GATED") = static_cast<int>(EstimatorStatus::ReadingGated);
    // The gate's current bound, as a multiple of i_peak.
    m.attr("WILD_CURRENT_MULTIPLE") = kWildCurrentMultiple;
    // The columns of EstimatorStream's records (one joint-state filter sample, flat).
    m.attr("RECORD_VALUES") = kRecordValues;
    m.def("fmu_signals", &fmu_signals,
          "Each FMU's inputs, outputs and batch-only signals (name, kind, unit, description), in value-reference "
          "order: the tables of src/hdjoint/*_signals.def.");
    m.def("motor_friction", &motor_friction_law, nb::arg("params"), nb::arg("omega_m"), nb::arg("t"),
          "Motor friction of eq. (2) (Coulomb, Stribeck, viscous; the drift scale max(0, 1 + Fc_drift*t)) at each "
          "speed and time since the start: the FMUs' code.");
    m.def("torque_constant_scale", &torque_constant_scale_law, nb::arg("params"), nb::arg("t"),
          "The torque constant's warm-up scale 1 + Kt_warmup*(1 - exp(-t/Kt_warmup_tc)) at each time since the "
          "start: the FMUs' code.");
    m.def("kinematic_error", &kinematic_error_law, nb::arg("params"), nb::arg("theta_m"), nb::arg("theta_l"),
          "The kinematic error of eq. (7) with its extra orders at each motor and link angle, rad.");
    m.def("cogging_torque", &cogging_law, nb::arg("params"), nb::arg("theta_m"),
          "Cogging torque on the motor at each motor angle (0 when off).");
    m.def("link_torque", &link_torque_law, nb::arg("params"), nb::arg("theta_l"), nb::arg("omega_l"),
          nb::arg("alpha_l"),
          "The transmitted torque the link's equation of motion needs (no external torque): "
          "Jl*alpha_l + Bl*omega_l + mgl*sin(theta_l) + link friction.");
    nb::class_<JointController>(m, "JointController",
                                "The C++ joint controller (JointController.fmu's law), one sample at a time.")
        .def("__init__",
             [](JointController* self, const std::map<std::string, double>& values, double start_time) {
                 new (self) JointController(controller_parameters_from(values), start_time);
             },
             nb::arg("params"), nb::arg("start_time") = 0.0)
        .def("command",
             [](JointController& c, double theta_m, double theta_ref, double omega_ref, double tau_fb) {
                 ControllerInputs in;
                 in.theta_m = theta_m;
                 in.tau_fb = tau_fb;
                 return c.command(in, theta_ref, omega_ref);
             },
             nb::arg("theta_m"), nb::arg("theta_ref"), nb::arg("omega_ref"), nb::arg("tau_fb") = 0.0,
             "The control law at one sample on an outside reference: the saturated current command.");
    m.def("parameter_table", &table, "The parameter table (name, unit, default, range, scope, description).");
    m.def("check_parameters", &check_parameters, nb::arg("params"),
          "validate() on a whole parameter set: the first problem (naming the parameter), or None.");
    m.def("run_estimator", &run_estimator, nb::arg("params"), nb::arg("time"), nb::arg("i_m"), nb::arg("theta_m"),
          nb::arg("theta_l"), nb::arg("smooth") = false,
          "Compliance model, paper UKF and the joint-state filter (tau_hat, tau_hat_std, tau_load) over a "
          "recording, with the FMU's sampling; smooth=True adds the RTS smoother's tau_smooth, tau_smooth_std.");
    nb::class_<EstimatorStream>(m, "EstimatorStream",
                                "run_estimator a block of rows at a time, the estimator carried across blocks "
                                "(the same numbers as on the whole recording).")
        .def(nb::init<const std::map<std::string, double>&, double, bool>(), nb::arg("params"),
             nb::arg("start_time"), nb::arg("keep_records") = false)
        .def("run", &EstimatorStream::run, nb::arg("time"), nb::arg("i_m"), nb::arg("theta_m"), nb::arg("theta_l"),
             nb::arg("end"),
             "The next block: row j steps to row j+1's time, the last row to `end`. The outputs, status and, with "
             "keep_records, last_record (per row, the index of the last filter sample its step ran, -1 before the "
             "filter starts) and records (the block's new filter samples, flat, for RtsSmoother).");
    nb::class_<RtsSmoother>(m, "RtsSmoother",
                            "The RTS smoother's backward pass over EstimatorStream's records, in blocks given last "
                            "block first.")
        .def(nb::init<const std::map<std::string, double>&>(), nb::arg("params"))
        .def("run", &RtsSmoother::run, nb::arg("records"),
             "tau_smooth and tau_smooth_std of each record of the block (the block just before the last one given).");
    m.def("compliance", &compliance, nb::arg("params"), nb::arg("i_m"), nb::arg("theta_m"), nb::arg("theta_l"),
          nb::arg("threads") = 1,
          "The estimator's compliance model, eq. (3)-(8) with hysteresis, backlash and the current delay, sample by "
          "sample: tau_compliance, dtheta_f, hysteresis_torque. Without a loop or a delay line the run is split over "
          "up to `threads` threads (the same numbers).");
    m.def("dahl", &dahl, nb::arg("x"), nb::arg("H"), nb::arg("sigma"),
          "Dahl hysteresis torque over a torsion sequence x (z = 0 at x[0]), the model's exact update.");
    m.def("time_estimator", &time_estimator, nb::arg("params"), nb::arg("samples"),
          "Seconds for `samples` estimator steps timed inside C++ (benchmark).");
    m.def("time_joint_filter", &time_joint_filter, nb::arg("params"), nb::arg("samples"),
          "Seconds for `samples` steps of the joint-state filter alone, timed inside C++ (benchmark).");
    m.def("simulate_joint", &simulate_joint, nb::arg("params"), nb::arg("time"), nb::arg("i_m"), nb::arg("tau_ext"),
          "The joint, open loop, with inputs held between rows; besides the FMU's outputs, tau_friction (motor side, "
          "viscous included), tau_cogging, tau_link_friction, z_hysteresis (Dahl + Bouc-Wen torque), "
          "elastic_torsion and friction_scale.");
}
