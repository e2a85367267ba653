#include "instance.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <new>
#include <stdexcept>

#include "crc32.h"

namespace hdjoint::fmu {

namespace {

const ModelInfo& info() { return this_model(); }

// Serialised layout: magic, version, state, time, start, stop, stop-defined,
// count, then the model's fields (Model::save), then the seal: the CRC-32 of
// every byte before it, as a double (an exact whole number). The magic and
// the version are this FMU's (ModelInfo), the magic's sign the glue's: another
// hdjoint FMU's state, or the other FMI version's, is refused. The seal is
// checked before anything else: an edit to any field, even to another valid
// value, is refused.
constexpr std::size_t kHeader = 8;
constexpr std::size_t kSeal = 1;

double seal_of(const double* values, std::size_t count) {
    return static_cast<double>(crc32(reinterpret_cast<const unsigned char*>(values), count * sizeof(double)));
}

}  // namespace

const char* StateMachine::name(unsigned s) const {
    for (const auto& [bit, text] : states)
        if (bit == s) return text;
    return "unknown";
}

bool StateMachine::is_state(double value) const {
    for (const auto& entry : states)
        if (value == static_cast<double>(entry.first)) return true;
    return false;
}

unsigned StateMachine::all() const {
    unsigned mask = 0;
    for (const auto& entry : states) mask |= entry.first;
    return mask;
}

std::string format_value(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

std::string instance_name_problem(const char* name) {
    if (!name || !*name) return "instanceName must not be empty";
    for (const char* c = name; *c; ++c)
        if (!std::isspace(static_cast<unsigned char>(*c))) return "";
    return "instanceName must contain a character that is not whitespace";
}

Instance::Instance(const StateMachine& m, std::string instance_name, Logger log_to, bool debug)
    : machine(m), name(std::move(instance_name)), logger(std::move(log_to)), debug_logging(debug),
      state(m.instantiated), model(info().create()) {}

void Instance::log(Code status, const char* category, const std::string& message) const {
    if (!logger) return;
    if (status == kOk && !debug_logging) return;
    logger(status, category, message);
}

Code Instance::error(const std::string& message) {
    log(kError, "logStatusError", message);
    state = machine.error;
    return kError;
}

bool Instance::allowed(const char* function, unsigned states) {
    if (state & states) return true;
    error(std::string(function) + " must not be called in state '" + machine.name(state) + "'");
    return false;
}

bool Instance::allowed(const char* function, unsigned states, bool model_exchange) {
    if (machine.model_exchange != model_exchange) {
        error(std::string(function) + " is a " + (model_exchange ? "Model Exchange" : "Co-Simulation") +
              " function, but this instance was instantiated for " +
              (machine.model_exchange ? "Model Exchange" : "Co-Simulation"));
        return false;
    }
    return allowed(function, states);
}

Code Instance::transition(const char* function, unsigned from, unsigned to) {
    if (!allowed(function, from)) return kError;
    state = to;
    return kOk;
}

Code Instance::with_function(const char* function, Result r) {
    if (r.status != Status::Ok) r.message = std::string(function) + ": " + r.message;
    return to_code(r);
}

Code Instance::to_code(const Result& r) {
    switch (r.status) {
        case Status::Ok: return kOk;
        case Status::Warning: log(kWarning, "logStatusWarning", r.message); return kWarning;
        case Status::Error: return error(r.message);
    }
    return kError;
}

std::string Instance::exception_message() {
    try {
        throw;
    } catch (const std::bad_alloc&) {
        return "out of memory";
    } catch (const std::exception& e) {
        return e.what();
    } catch (...) {
        return "unknown failure";
    }
}

Code Instance::set_debug_logging(const char* function, bool on, std::size_t n, const char* const categories[]) {
    if (!allowed(function, machine.all())) return kError;
    for (std::size_t i = 0; i < n; ++i) {
        const std::string cat = categories && categories[i] ? categories[i] : "";
        if (cat != "logStatusWarning" && cat != "logStatusError" && cat != "logAll")
            return error(std::string(function) + ": unknown log category '" + cat + "'");
    }
    debug_logging = on;
    return kOk;
}

Code Instance::setup_experiment(const char* function, double start, bool stop_defined, double stop) {
    if (!std::isfinite(start)) return error(std::string(function) + ": startTime = " + format_value(start) + " is not finite");
    // A stop time must be a time: an infinite one could not be saved in an
    // FMU state and restored (state_problem refuses it), so it is refused here.
    if (stop_defined && !std::isfinite(stop))
        return error(std::string(function) + ": stopTime = " + format_value(stop) +
                     " is not finite (leave the stop time undefined for an open-ended run)");
    if (stop_defined && !(stop >= start))
        return error(std::string(function) + ": stopTime = " + format_value(stop) + " is before startTime = " +
                     format_value(start));
    start_time = time = start;
    stop_time_defined = stop_defined;
    stop_time = stop;
    return kOk;
}

Code Instance::initialize(const char* function, unsigned next) {
    return guarded(function, [&] {
        const Code s = to_code(model->initialize(start_time));
        if (s != kError) state = next;
        return s;
    });
}

Code Instance::reset(const char* function) {
    if (!allowed(function, machine.all())) return kError;
    return guarded(function, [&] {
        model->reset();
        state = machine.instantiated;
        time = start_time = stop_time = 0.0;
        stop_time_defined = false;
        return kOk;
    });
}

Code Instance::get_reals(const char* function, const unsigned vr[], std::size_t nvr, double values[]) {
    if (nvr > 0 && (!vr || !values)) return error(std::string(function) + ": null array argument");
    return guarded(function, [&] {
        for (std::size_t i = 0; i < nvr; ++i) {
            if (time_is_variable && vr[i] == kTimeReference) {
                values[i] = time;
                continue;
            }
            if (!find_variable(info(), vr[i]))
                return error(std::string(function) + ": no variable has value reference " + std::to_string(vr[i]));
            values[i] = model->get(vr[i]);
        }
        return kOk;
    });
}

Code Instance::set_reals(const char* function, const unsigned vr[], std::size_t nvr, const double values[],
                         unsigned parameter_states) {
    if (nvr > 0 && (!vr || !values)) return error(std::string(function) + ": null array argument");
    const std::string fn = function;
    return guarded(function, [&] {
        Code worst = kOk;
        for (std::size_t i = 0; i < nvr; ++i) {
            const Variable* v = find_variable(info(), vr[i]);
            if (time_is_variable && vr[i] == kTimeReference)
                return error(fn + ": time is the independent variable and cannot be set");
            if (!v) return error(fn + ": no variable has value reference " + std::to_string(vr[i]));
            const std::string what = v->name + " = " + format_value(values[i]);
            if (v->causality == Causality::Output) return error(fn + ": " + v->name + " is an output and cannot be set");
            if (v->causality == Causality::Local) return error(fn + ": " + v->name + " is computed and cannot be set");
            if (v->causality == Causality::Parameter && !(state & parameter_states))
                return error(fn + ": parameter " + v->name + " is fixed after initialization");
            if (!std::isfinite(values[i])) return error(fn + ": " + what + " is not finite");
            if (values[i] < v->min || values[i] > v->max)
                return error(fn + ": " + what + " is outside its valid range [" + format_value(v->min) + ", " +
                             format_value(v->max) + "] " + v->unit);
            const Code s = to_code(model->set(vr[i], values[i]));
            if (s == kError) return s;
            if (s > worst) worst = s;
        }
        return worst;
    });
}

Code Instance::no_such_variables(const char* function, unsigned states, std::size_t nvr, const char* type) {
    if (!allowed(function, states)) return kError;
    if (nvr == 0) return kOk;
    return error(std::string(function) + ": this FMU has no " + type + " variables");
}

Code Instance::do_step(const char* function, double t, double h) {
    const std::string fn = function;
    // The step size must be > 0 (FMI 2.0.4 4.2.2, FMI 3.0 4.2.1): 0 and -0 are no step.
    if (!std::isfinite(t) || !std::isfinite(h) || !(h > 0.0))
        return error(fn + ": communication point " + format_value(t) + " with step size " + format_value(h) +
                     " is not a forward step (the step size must be > 0)");
    // Masters accumulate communication points in floating point; accept
    // round-off (and re-synchronise to the master's time) but not a jump.
    // Relative to the time only: a long step must not widen it.
    const double tolerance = 1e-9 * std::max(1.0, std::fabs(t));
    if (std::fabs(t - time) > tolerance)
        return error(fn + ": expected communication point " + format_value(time) + " but got " + format_value(t));
    if (stop_time_defined && t + h > stop_time + 1e-9 * std::max(1.0, std::fabs(stop_time)))
        return error(fn + ": the step to " + format_value(t + h) + " goes past stopTime " + format_value(stop_time));
    return guarded(function, [&] {
        const Code s = to_code(model->do_step(t, h));
        if (s != kError) time = t + h;
        return s;
    });
}

// ---- Model Exchange ---------------------------------------------------------

Code Instance::check_vector(const char* function, const void* array, std::size_t n, std::size_t expected) {
    if (n != expected)
        return error(std::string(function) + ": " + std::to_string(n) + " values, but this model has " +
                     std::to_string(expected));
    if (n > 0 && !array) return error(std::string(function) + ": null array argument");
    if (!model->initialized())
        return error(std::string(function) + ": the model is built when initialisation ends; call it after "
                     "ExitInitializationMode");
    return kOk;
}

Code Instance::set_time(const char* function, double t) {
    if (!std::isfinite(t) || t < start_time)
        return error(std::string(function) + ": time " + format_value(t) + " is not a finite time at or after the "
                     "start time " + format_value(start_time));
    if (!model->initialized())
        return error(std::string(function) + ": the model is built when initialisation ends; call it after "
                     "ExitInitializationMode");
    return guarded(function, [&] {
        const Code s = to_code(model->set_time(t - start_time));
        if (s != kError) time = t;
        return s;
    });
}

Code Instance::set_states(const char* function, const double x[], std::size_t n) {
    if (const Code c = check_vector(function, x, n, info().continuous_states); c != kOk) return c;
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(x[i]))
            return error(std::string(function) + ": state " + std::to_string(i) + " = " + format_value(x[i]) +
                         " is not finite");
    return guarded(function, [&] { return with_function(function, model->set_states(x)); });
}

Code Instance::get_vector(const char* function, Vector which, double out[], std::size_t n) {
    const std::size_t expected =
        which == Vector::EventIndicators ? info().event_indicators : info().continuous_states;
    if (which == Vector::Nominals && n == expected && (n == 0 || out)) {
        model->nominals(out);  // fixed by the parameters: known before initialisation too
        return kOk;
    }
    if (const Code c = check_vector(function, out, n, expected); c != kOk) return c;
    return guarded(function, [&] {
        Result r;
        switch (which) {
            case Vector::States: r = model->get_states(out); break;
            case Vector::Derivatives: r = model->derivatives(out); break;
            case Vector::EventIndicators: r = model->event_indicators(out); break;
            case Vector::Nominals: break;
        }
        return with_function(function, r);
    });
}

// ---- FMU state ------------------------------------------------------------

double Instance::magic() const { return machine.magic_sign * info().state_magic; }

// What is wrong with a saved state (glue fields and the model's), or "".
// The model is checked by loading it into a scratch instance.
std::string Instance::state_problem(const SavedState& s) const {
    if (!std::isfinite(s.time) || !std::isfinite(s.start_time) || s.time < s.start_time)
        return "time " + format_value(s.time) + " with start time " + format_value(s.start_time) +
               " is not a finite time at or after the start";
    if (s.stop_time_defined && !(std::isfinite(s.stop_time) && s.stop_time >= s.start_time))
        return "stop time " + format_value(s.stop_time) + " is not a finite time at or after the start";
    auto scratch = info().create();
    const Result loaded = scratch->load(s.model);
    if (loaded.status == Status::Error) return loaded.message;
    if ((s.state & machine.needs_model) && !scratch->initialized())
        return std::string("state '") + machine.name(s.state) + "' needs an initialised model, but the model was never "
               "initialised";
    // Before initialisation nothing has run: no model is built (reset() drops
    // it) and the time is still the start time.
    if (s.state & machine.before_init) {
        if (scratch->initialized())
            return std::string("state '") + machine.name(s.state) + "' comes before initialisation, but the model "
                   "in it was initialised";
        if (s.time != s.start_time)
            return std::string("state '") + machine.name(s.state) + "' comes before any step, but its time " +
                   format_value(s.time) + " is not its start time " + format_value(s.start_time);
    }
    return "";
}

Code Instance::get_state(const char* function, SavedState** handle) {
    if (!allowed(function, machine.all())) return kError;
    if (!handle) return error(std::string(function) + ": FMUstate is null");
    return guarded(function, [&] {
        SavedState* saved = *handle ? *handle : new SavedState();
        *saved = {state, time, start_time, stop_time, stop_time_defined, model->save()};
        *handle = saved;
        return kOk;
    });
}

Code Instance::set_state(const char* function, const SavedState* saved) {
    if (!allowed(function, machine.all())) return kError;
    if (!saved) return error(std::string(function) + ": FMUstate is null");
    return guarded(function, [&] {
        const std::string problem = state_problem(*saved);
        if (!problem.empty()) return error(std::string(function) + ": the state does not fit this model: " + problem);
        const Result loaded = model->load(saved->model);
        if (loaded.status == Status::Error)
            return error(std::string(function) + ": the state does not fit this model: " + loaded.message);
        state = saved->state;
        time = saved->time;
        start_time = saved->start_time;
        stop_time = saved->stop_time;
        stop_time_defined = saved->stop_time_defined;
        return kOk;
    });
}

Code Instance::free_state(const char* function, SavedState** handle) {
    if (!allowed(function, machine.all())) return kError;
    if (handle) {
        delete *handle;
        *handle = nullptr;
    }
    return kOk;
}

std::vector<double> Instance::flatten(const SavedState& s) const {
    std::vector<double> v = {magic(), info().state_version, static_cast<double>(s.state), s.time, s.start_time,
                             s.stop_time, s.stop_time_defined ? 1.0 : 0.0, static_cast<double>(s.model.size())};
    v.insert(v.end(), s.model.begin(), s.model.end());
    v.push_back(seal_of(v.data(), v.size()));
    return v;
}

Code Instance::serialized_size(const char* function, const SavedState* saved, std::size_t* size) {
    if (!allowed(function, machine.all())) return kError;
    if (!saved || !size) return error(std::string(function) + ": null argument");
    *size = flatten(*saved).size() * sizeof(double);
    return kOk;
}

Code Instance::serialize(const char* function, const SavedState* saved, unsigned char* bytes, std::size_t size) {
    if (!allowed(function, machine.all())) return kError;
    if (!saved || !bytes) return error(std::string(function) + ": null argument");
    const std::vector<double> v = flatten(*saved);
    if (size != v.size() * sizeof(double))
        return error(std::string(function) + ": size " + std::to_string(size) + " does not match " +
                     std::to_string(v.size() * sizeof(double)));
    std::memcpy(bytes, v.data(), size);
    return kOk;
}

Code Instance::deserialize(const char* function, const unsigned char* bytes, std::size_t size, SavedState** handle) {
    if (!allowed(function, machine.all())) return kError;
    if (!bytes || !handle) return error(std::string(function) + ": null argument");
    const std::string fn = function;
    return guarded(function, [&] {
        const std::size_t n = size / sizeof(double);
        if (size % sizeof(double) != 0 || n < kHeader + kSeal)
            return error(fn + ": truncated state (" + std::to_string(size) + " bytes)");
        std::vector<double> v(n);
        std::memcpy(v.data(), bytes, size);
        if (v[n - 1] != seal_of(v.data(), n - kSeal))
            return error(fn + ": the state's CRC-32 seal does not match its contents: it was edited, truncated or "
                         "damaged after it was serialised");
        v.pop_back();
        if (v[0] != magic()) {
            const bool other_version = v[0] == -magic();
            return error(fn + ": not a state of this FMU (" + info().model_identifier +
                         (other_version ? "): it was saved by the FMU's other FMI version" : ")"));
        }
        if (v[1] != info().state_version)
            return error(fn + ": state version " + format_value(v[1]) + " is not this binary's version " +
                         format_value(info().state_version));
        if (v[7] != static_cast<double>(v.size() - kHeader))
            return error(fn + ": truncated state (its header counts " + format_value(v[7]) + " model values, " +
                         std::to_string(v.size() - kHeader) + " follow)");
        if (!machine.is_state(v[2]) || (v[6] != 0.0 && v[6] != 1.0))
            return error(fn + ": state-machine value " + format_value(v[2]) + " or stop-time flag " +
                         format_value(v[6]) + " is not valid");
        auto saved = std::make_unique<SavedState>();
        saved->state = static_cast<unsigned>(v[2]);
        saved->time = v[3];
        saved->start_time = v[4];
        saved->stop_time = v[5];
        saved->stop_time_defined = v[6] != 0.0;
        saved->model.assign(v.begin() + kHeader, v.end());
        const std::string problem = state_problem(*saved);
        if (!problem.empty()) return error(fn + ": the state does not fit this model: " + problem);
        delete *handle;
        *handle = saved.release();
        return kOk;
    });
}

}  // namespace hdjoint::fmu
