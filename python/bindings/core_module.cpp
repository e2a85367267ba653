// hdjoint._core: the batch path to the C++ core, for work that runs the model
// many times (estimation over recordings, diagnosis). Same code as the FMUs.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/map.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "hdjoint/compliance_model.h"
#include "hdjoint/hysteresis.h"
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

// The estimator over a recording, with the FMU's timing: row j is a
// communication point; its step [t_j, t_j+1) runs the samples start + k*Ts
// inside it on row j's inputs, and row j's outputs are those after the step
// (the last row steps by Ts). With `smooth`, the joint-state filter's
// samples are kept and an RTS smoother run backwards over them gives
// tau_smooth (and tau_smooth_std): row j gets the smoothed torque of the
// last sample its step ran (the compliance torque before the filter starts).
std::map<std::string, OutArray> run_estimator(const std::map<std::string, double>& values, Array time, Array i_m,
                                              Array theta_m, Array theta_l, bool smooth) {
    const std::size_t n = time.shape(0);
    check_lengths(n, {i_m.shape(0), theta_m.shape(0), theta_l.shape(0)});
    const Parameters p = parameters_from(values, true, false);
    TorqueEstimator estimator(p);
    std::vector<double> tau_ukf(n), tau_c(n), omega(n), dtheta_f(n), std_ukf(n), nis(n), status(n), z(n);
    std::vector<double> tau_hat(n), std_hat(n), load(n);
    std::vector<JointFilterRecord> records;
    std::vector<long> last_record(n, -1);  // per row: index of the last filter sample its step ran
    if (smooth) records.reserve(n);
    const double t0 = time(0), tolerance = 1e-6 * p.Ts;
    long next = 0;
    {
        nb::gil_scoped_release release;
        for (std::size_t j = 0; j < n; ++j) {
            const double end = j + 1 < n ? time(j + 1) : time(j) + p.Ts;
            const EstimatorInputs in{i_m(j), theta_m(j), theta_l(j)};
            int worst = 0;
            while (t0 + static_cast<double>(next) * p.Ts < end - tolerance) {
                std::string message;
                const EstimatorStatus s = estimator.step(in, &message);
                if (!recoverable(s)) {
                    nb::gil_scoped_acquire acquire;
                    throw std::runtime_error("row " + std::to_string(j) + " (time " + std::to_string(time(j)) +
                                             " s): " + message);
                }
                worst = std::max(worst, static_cast<int>(s));
                ++next;
                if (smooth && estimator.joint_filter().started() &&
                    (records.empty() || estimator.joint_filter().record().predicted)) {
                    records.push_back(estimator.joint_filter().record());
                }
            }
            last_record[j] = static_cast<long>(records.size()) - 1;
            const EstimatorOutputs& o = estimator.outputs();
            tau_ukf[j] = o.tau_ukf;
            tau_c[j] = o.tau_compliance;
            omega[j] = o.omega_m;
            dtheta_f[j] = o.dtheta_f;
            std_ukf[j] = o.tau_ukf_std;
            nis[j] = o.nis;
            z[j] = o.hysteresis_torque;
            tau_hat[j] = o.tau_hat;
            std_hat[j] = o.tau_hat_std;
            load[j] = o.load;
            status[j] = worst;
        }
    }
    std::map<std::string, OutArray> out;
    out.emplace("tau_ukf", make_array(std::move(tau_ukf)));
    out.emplace("tau_compliance", make_array(std::move(tau_c)));
    out.emplace("omega_m", make_array(std::move(omega)));
    out.emplace("dtheta_f", make_array(std::move(dtheta_f)));
    out.emplace("tau_ukf_std", make_array(std::move(std_ukf)));
    out.emplace("nis", make_array(std::move(nis)));
    out.emplace("status", make_array(std::move(status)));
    out.emplace("hysteresis_torque", make_array(std::move(z)));
    if (smooth) {
        const SmoothedTorque sm = smooth_joint_states(records, p);
        std::vector<double> tau_s(n), std_s(n);
        for (std::size_t j = 0; j < n; ++j) {
            const long r = last_record[j];
            tau_s[j] = r >= 0 ? sm.tau[static_cast<std::size_t>(r)] : tau_hat[j];
            std_s[j] = r >= 0 ? sm.tau_std[static_cast<std::size_t>(r)] : std_hat[j];
        }
        out.emplace("tau_smooth", make_array(std::move(tau_s)));
        out.emplace("tau_smooth_std", make_array(std::move(std_s)));
    }
    out.emplace("tau_hat", make_array(std::move(tau_hat)));
    out.emplace("tau_hat_std", make_array(std::move(std_hat)));
    out.emplace("tau_load", make_array(std::move(load)));
    return out;
}

// The estimator's compliance model, eq. (3)-(8) with the beyond-paper terms,
// run sample by sample (hysteresis and the current delay carry state; one
// row is one estimator sample). NaN where the torsion is singular.
std::map<std::string, OutArray> compliance(const std::map<std::string, double>& values, Array i_m, Array theta_m,
                                           Array theta_l) {
    const std::size_t n = i_m.shape(0);
    check_lengths(n, {theta_m.shape(0), theta_l.shape(0)});
    const Parameters p = parameters_from(values, true, false);
    ComplianceModel model(p);
    std::vector<double> tau(n), dtheta_f(n), z(n);
    for (std::size_t j = 0; j < n; ++j) {
        const ComplianceSample c = model.step(i_m(j), theta_m(j), theta_l(j));
        tau[j] = c.valid ? c.tau : std::nan("");
        dtheta_f[j] = c.dtheta_f;
        z[j] = c.z;
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
            omega_l[j] = o.omega_l;
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
    m.def("parameter_table", &table, "The parameter table (name, unit, default, range, scope, description).");
    m.def("run_estimator", &run_estimator, nb::arg("params"), nb::arg("time"), nb::arg("i_m"), nb::arg("theta_m"),
          nb::arg("theta_l"), nb::arg("smooth") = false,
          "Compliance model, paper UKF and the joint-state filter (tau_hat, tau_hat_std, tau_load) over a "
          "recording, with the FMU's sampling; smooth=True adds the RTS smoother's tau_smooth, tau_smooth_std.");
    m.def("compliance", &compliance, nb::arg("params"), nb::arg("i_m"), nb::arg("theta_m"), nb::arg("theta_l"),
          "The estimator's compliance model, eq. (3)-(8) with hysteresis, backlash and the current delay, sample by "
          "sample: tau_compliance, dtheta_f, hysteresis_torque.");
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
