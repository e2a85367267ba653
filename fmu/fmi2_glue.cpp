// The FMI 2.0 Co-Simulation interface, once for every hdjoint FMU. It owns
// the FMI state machine, argument and time checks, logging, and FMU state
// copies; the physics is behind the Model of this_model(). Exceptions never
// cross the C boundary: they become fmi2Error and a logged message.
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "crc32.h"
#include "description.h"
#include "fmi2Functions.h"
#include "model.h"

namespace {

using hdjoint::fmu::Causality;
using hdjoint::fmu::Model;
using hdjoint::fmu::ModelInfo;
using hdjoint::fmu::Result;
using hdjoint::fmu::Status;
using hdjoint::fmu::Variable;

// States of the Co-Simulation state machine (FMI 2.0, section 4.2.4), as bits
// so each function names the set of states it may be called in.
enum State : unsigned {
    kInstantiated = 1u << 0,
    kInitializationMode = 1u << 1,
    kStepComplete = 1u << 2,
    kStepFailed = 1u << 3,
    kTerminated = 1u << 4,
    kError = 1u << 5,
};
constexpr unsigned kAnyButFatal = kInstantiated | kInitializationMode | kStepComplete | kStepFailed | kTerminated | kError;
constexpr unsigned kCanGet = kInitializationMode | kStepComplete | kStepFailed | kTerminated | kError;
constexpr unsigned kCanSet = kInstantiated | kInitializationMode | kStepComplete;
// fmi2Get*Status: after a step, not in the error state (FMI 2.0, table in 4.2.4).
constexpr unsigned kCanGetStatus = kStepComplete | kStepFailed | kTerminated;
// States that need an initialised model (doStep, outputs from a run).
constexpr unsigned kNeedsModel = kStepComplete | kStepFailed | kTerminated;

const char* state_name(unsigned s) {
    switch (s) {
        case kInstantiated: return "instantiated";
        case kInitializationMode: return "initialization mode";
        case kStepComplete: return "step complete";
        case kStepFailed: return "step failed";
        case kTerminated: return "terminated";
        case kError: return "error";
    }
    return "unknown";
}

struct Instance {
    std::string name;
    fmi2CallbackLogger logger = nullptr;
    fmi2ComponentEnvironment environment = nullptr;
    bool debug_logging = false;
    unsigned state = kInstantiated;
    double time = 0.0;
    double start_time = 0.0;
    double stop_time = 0.0;
    bool stop_time_defined = false;
    std::unique_ptr<Model> model;

    void log(fmi2Status status, const char* category, const std::string& message) const {
        if (!logger) return;
        if (status == fmi2OK && !debug_logging) return;
        // The message goes through "%s": the logger formats printf-style.
        logger(environment, name.c_str(), status, category, "%s", message.c_str());
    }
    fmi2Status error(const std::string& message) {
        log(fmi2Error, "logStatusError", message);
        state = kError;
        return fmi2Error;
    }
};

// The saved copy behind an fmi2FMUstate.
struct SavedState {
    unsigned state;
    double time, start_time, stop_time;
    bool stop_time_defined;
    std::vector<double> model;
};

const ModelInfo& info() { return hdjoint::fmu::this_model(); }

// Check the instance and that `function` may be called in its state.
bool allowed(Instance* instance, const char* function, unsigned states) {
    if (!instance) return false;
    if (instance->state & states) return true;
    instance->error(std::string(function) + " must not be called in state '" + state_name(instance->state) + "'");
    return false;
}

fmi2Status to_fmi(Instance* instance, const Result& r) {
    switch (r.status) {
        case Status::Ok: return fmi2OK;
        case Status::Warning: instance->log(fmi2Warning, "logStatusWarning", r.message); return fmi2Warning;
        case Status::Error: return instance->error(r.message);
    }
    return fmi2Error;
}

// Run `body`, turning any exception into fmi2Error with its message.
template <class Body>
fmi2Status guarded(Instance* instance, const char* function, Body body) {
    try {
        return body();
    } catch (const std::bad_alloc&) {
        return instance ? instance->error(std::string(function) + ": out of memory") : fmi2Error;
    } catch (const std::exception& e) {
        return instance ? instance->error(std::string(function) + ": " + e.what()) : fmi2Error;
    } catch (...) {
        return instance ? instance->error(std::string(function) + ": unknown failure") : fmi2Error;
    }
}

std::string format_value(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

// The Integer, Boolean and String calls: legal in `states`, but this FMU has no such variables.
fmi2Status no_such_variables(fmi2Component c, const char* function, unsigned states, size_t nvr, const char* type) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, function, states)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return in->error(std::string(function) + ": this FMU has no " + type + " variables");
}

// Serialised layout: magic, version, state, time, start, stop, stop-defined,
// count, then the model's fields (Model::save), then the seal: the CRC-32 of
// every byte before it, as a double (an exact whole number). The magic and
// the version are this FMU's (ModelInfo): another hdjoint FMU's state is
// refused. The seal is checked before anything else: an edit to any field,
// even to another valid value, is refused.
constexpr std::size_t kHeader = 8;
constexpr std::size_t kSeal = 1;

double seal_of(const double* values, std::size_t count) {
    return static_cast<double>(hdjoint::fmu::crc32(reinterpret_cast<const unsigned char*>(values),
                                                   count * sizeof(double)));
}

bool is_state(double s) {
    for (unsigned k : {kInstantiated, kInitializationMode, kStepComplete, kStepFailed, kTerminated, kError})
        if (s == static_cast<double>(k)) return true;
    return false;
}

// What is wrong with a saved state (glue fields and the model's), or "".
// The model is checked by loading it into a scratch instance.
std::string state_problem(const SavedState& s) {
    if (!std::isfinite(s.time) || !std::isfinite(s.start_time) || s.time < s.start_time)
        return "time " + format_value(s.time) + " with start time " + format_value(s.start_time) +
               " is not a finite time at or after the start";
    if (s.stop_time_defined && !(std::isfinite(s.stop_time) && s.stop_time >= s.start_time))
        return "stop time " + format_value(s.stop_time) + " is not a finite time at or after the start";
    auto scratch = info().create();
    const Result loaded = scratch->load(s.model);
    if (loaded.status == Status::Error) return loaded.message;
    if ((s.state & kNeedsModel) && !scratch->initialized())
        return std::string("state '") + state_name(s.state) + "' needs an initialised model, but the model was never "
               "initialised";
    // Before fmi2ExitInitializationMode nothing has run: no model is built
    // (reset() drops it) and the time is still the start time.
    if (s.state & (kInstantiated | kInitializationMode)) {
        if (scratch->initialized())
            return std::string("state '") + state_name(s.state) + "' comes before initialisation, but the model "
                   "in it was initialised";
        if (s.time != s.start_time)
            return std::string("state '") + state_name(s.state) + "' comes before any step, but its time " +
                   format_value(s.time) + " is not its start time " + format_value(s.start_time);
    }
    return "";
}

// A call that only moves the state machine, from one of `from` to `to`.
fmi2Status transition(fmi2Component c, const char* function, unsigned from, State to) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, function, from)) return fmi2Error;
    in->state = to;
    return fmi2OK;
}

// An fmi2Get*Status call: after a step (not in the error state), the one
// kind this type reports (`known`, with `answer(instance)`), fmi2Discard for
// any other: doStep is synchronous, so nothing is ever pending.
template <class T>
fmi2Status report_status(fmi2Component c, const char* function, fmi2StatusKind, T*) {
    auto* in = static_cast<Instance*>(c);
    return allowed(in, function, kCanGetStatus) ? fmi2Discard : fmi2Error;
}
template <class T, class Answer>
fmi2Status report_status(fmi2Component c, const char* function, fmi2StatusKind asked, T* value,
                         fmi2StatusKind known, Answer answer) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, function, kCanGetStatus)) return fmi2Error;
    if (asked != known || !value) return fmi2Discard;
    *value = answer(*in);
    return fmi2OK;
}

}  // namespace

extern "C" {

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String /*fmuResourceLocation*/, const fmi2CallbackFunctions* functions,
                              fmi2Boolean /*visible*/, fmi2Boolean loggingOn) {
    fmi2CallbackLogger logger = functions ? functions->logger : nullptr;
    fmi2ComponentEnvironment env = functions ? functions->componentEnvironment : nullptr;
    const char* name = instanceName ? instanceName : "";
    auto refuse = [&](const std::string& message) -> fmi2Component {
        if (logger) logger(env, name, fmi2Error, "logStatusError", "%s", message.c_str());
        return nullptr;
    };
    try {
        if (!instanceName || !*instanceName) return refuse("fmi2Instantiate: instanceName must not be empty");
        if (fmuType != fmi2CoSimulation)
            return refuse("fmi2Instantiate: " + info().model_identifier + " supports Co-Simulation only");
        const std::string expected = hdjoint::fmu::guid(info());
        if (!fmuGUID || expected != fmuGUID)
            return refuse(std::string("fmi2Instantiate: GUID ") + (fmuGUID ? fmuGUID : "(null)") +
                          " does not match this binary's " + expected);
        auto instance = std::make_unique<Instance>();
        instance->name = name;
        instance->logger = logger;
        instance->environment = env;
        instance->debug_logging = loggingOn != fmi2False;
        instance->model = info().create();
        return instance.release();
    } catch (const std::exception& e) {
        return refuse(std::string("fmi2Instantiate: ") + e.what());
    }
}

void fmi2FreeInstance(fmi2Component c) { delete static_cast<Instance*>(c); }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2SetDebugLogging", kAnyButFatal)) return fmi2Error;
    for (size_t i = 0; i < nCategories; ++i) {
        const std::string cat = categories && categories[i] ? categories[i] : "";
        if (cat != "logStatusWarning" && cat != "logStatusError" && cat != "logAll")
            return in->error("fmi2SetDebugLogging: unknown log category '" + cat + "'");
    }
    in->debug_logging = loggingOn != fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean /*toleranceDefined*/, fmi2Real /*tolerance*/,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2SetupExperiment", kInstantiated)) return fmi2Error;
    if (!std::isfinite(startTime)) return in->error("fmi2SetupExperiment: startTime = " + format_value(startTime) + " is not finite");
    if (stopTimeDefined && !(stopTime >= startTime))
        return in->error("fmi2SetupExperiment: stopTime = " + format_value(stopTime) + " is before startTime = " +
                         format_value(startTime));
    in->start_time = in->time = startTime;
    in->stop_time_defined = stopTimeDefined != fmi2False;
    in->stop_time = stopTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    return transition(c, "fmi2EnterInitializationMode", kInstantiated, kInitializationMode);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2ExitInitializationMode", kInitializationMode)) return fmi2Error;
    return guarded(in, "fmi2ExitInitializationMode", [&] {
        const fmi2Status s = to_fmi(in, in->model->initialize(in->start_time));
        if (s != fmi2Error) in->state = kStepComplete;
        return s;
    });
}

// Not in the error state (FMI 2.0, 4.2.4): only after a step.
fmi2Status fmi2Terminate(fmi2Component c) {
    return transition(c, "fmi2Terminate", kStepComplete | kStepFailed, kTerminated);
}

fmi2Status fmi2Reset(fmi2Component c) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2Reset", kAnyButFatal)) return fmi2Error;
    return guarded(in, "fmi2Reset", [&] {
        in->model->reset();
        in->state = kInstantiated;
        in->time = in->start_time = in->stop_time = 0.0;
        in->stop_time_defined = false;
        return fmi2OK;
    });
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2GetReal", kCanGet)) return fmi2Error;
    if (nvr > 0 && (!vr || !value)) return in->error("fmi2GetReal: null array argument");
    return guarded(in, "fmi2GetReal", [&] {
        for (size_t i = 0; i < nvr; ++i) {
            if (!hdjoint::fmu::find_variable(info(), vr[i]))
                return in->error("fmi2GetReal: no variable has value reference " + std::to_string(vr[i]));
            value[i] = in->model->get(vr[i]);
        }
        return fmi2OK;
    });
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2SetReal", kCanSet)) return fmi2Error;
    if (nvr > 0 && (!vr || !value)) return in->error("fmi2SetReal: null array argument");
    return guarded(in, "fmi2SetReal", [&] {
        fmi2Status worst = fmi2OK;
        for (size_t i = 0; i < nvr; ++i) {
            const Variable* v = hdjoint::fmu::find_variable(info(), vr[i]);
            if (!v) return in->error("fmi2SetReal: no variable has value reference " + std::to_string(vr[i]));
            const std::string what = v->name + " = " + format_value(value[i]);
            if (v->causality == Causality::Output) return in->error("fmi2SetReal: " + v->name + " is an output and cannot be set");
            if (v->causality == Causality::Parameter && !(in->state & (kInstantiated | kInitializationMode)))
                return in->error("fmi2SetReal: parameter " + v->name + " is fixed after initialization");
            if (!std::isfinite(value[i])) return in->error("fmi2SetReal: " + what + " is not finite");
            if (value[i] < v->min || value[i] > v->max)
                return in->error("fmi2SetReal: " + what + " is outside its valid range [" + format_value(v->min) +
                                 ", " + format_value(v->max) + "] " + v->unit);
            const fmi2Status s = to_fmi(in, in->model->set(vr[i], value[i]));
            if (s == fmi2Error) return s;
            if (s > worst) worst = s;
        }
        return worst;
    });
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference[], size_t nvr, fmi2Integer[]) {
    return no_such_variables(c, "fmi2GetInteger", kCanGet, nvr, "Integer");
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference[], size_t nvr, fmi2Boolean[]) {
    return no_such_variables(c, "fmi2GetBoolean", kCanGet, nvr, "Boolean");
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference[], size_t nvr, fmi2String[]) {
    return no_such_variables(c, "fmi2GetString", kCanGet, nvr, "String");
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference[], size_t nvr, const fmi2Integer[]) {
    return no_such_variables(c, "fmi2SetInteger", kCanSet, nvr, "Integer");
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference[], size_t nvr, const fmi2Boolean[]) {
    return no_such_variables(c, "fmi2SetBoolean", kCanSet, nvr, "Boolean");
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference[], size_t nvr, const fmi2String[]) {
    return no_such_variables(c, "fmi2SetString", kCanSet, nvr, "String");
}

// ---- FMU state ------------------------------------------------------------

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2GetFMUstate", kAnyButFatal)) return fmi2Error;
    if (!FMUstate) return in->error("fmi2GetFMUstate: FMUstate is null");
    return guarded(in, "fmi2GetFMUstate", [&] {
        auto* saved = static_cast<SavedState*>(*FMUstate);
        if (!saved) saved = new SavedState();
        *saved = {in->state, in->time, in->start_time, in->stop_time, in->stop_time_defined, in->model->save()};
        *FMUstate = saved;
        return fmi2OK;
    });
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2SetFMUstate", kAnyButFatal)) return fmi2Error;
    if (!FMUstate) return in->error("fmi2SetFMUstate: FMUstate is null");
    return guarded(in, "fmi2SetFMUstate", [&] {
        const auto* saved = static_cast<const SavedState*>(FMUstate);
        const std::string problem = state_problem(*saved);
        if (!problem.empty()) return in->error("fmi2SetFMUstate: the state does not fit this model: " + problem);
        const Result loaded = in->model->load(saved->model);
        if (loaded.status == Status::Error)
            return in->error("fmi2SetFMUstate: the state does not fit this model: " + loaded.message);
        in->state = saved->state;
        in->time = saved->time;
        in->start_time = saved->start_time;
        in->stop_time = saved->stop_time;
        in->stop_time_defined = saved->stop_time_defined;
        return fmi2OK;
    });
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2FreeFMUstate", kAnyButFatal)) return fmi2Error;
    if (FMUstate) {
        delete static_cast<SavedState*>(*FMUstate);
        *FMUstate = nullptr;
    }
    return fmi2OK;
}

static std::vector<double> flatten(const SavedState& s) {
    std::vector<double> v = {info().state_magic, info().state_version, static_cast<double>(s.state), s.time,
                             s.start_time, s.stop_time, s.stop_time_defined ? 1.0 : 0.0,
                             static_cast<double>(s.model.size())};
    v.insert(v.end(), s.model.begin(), s.model.end());
    v.push_back(seal_of(v.data(), v.size()));
    return v;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2SerializedFMUstateSize", kAnyButFatal)) return fmi2Error;
    if (!FMUstate || !size) return in->error("fmi2SerializedFMUstateSize: null argument");
    *size = flatten(*static_cast<const SavedState*>(FMUstate)).size() * sizeof(double);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2SerializeFMUstate", kAnyButFatal)) return fmi2Error;
    if (!FMUstate || !serializedState) return in->error("fmi2SerializeFMUstate: null argument");
    const std::vector<double> v = flatten(*static_cast<const SavedState*>(FMUstate));
    if (size != v.size() * sizeof(double))
        return in->error("fmi2SerializeFMUstate: size " + std::to_string(size) + " does not match " +
                         std::to_string(v.size() * sizeof(double)));
    std::memcpy(serializedState, v.data(), size);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate* FMUstate) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2DeSerializeFMUstate", kAnyButFatal)) return fmi2Error;
    if (!serializedState || !FMUstate) return in->error("fmi2DeSerializeFMUstate: null argument");
    return guarded(in, "fmi2DeSerializeFMUstate", [&] {
        const size_t n = size / sizeof(double);
        if (size % sizeof(double) != 0 || n < kHeader + kSeal)
            return in->error("fmi2DeSerializeFMUstate: truncated state (" + std::to_string(size) + " bytes)");
        std::vector<double> v(n);
        std::memcpy(v.data(), serializedState, size);
        if (v[n - 1] != seal_of(v.data(), n - kSeal))
            return in->error("fmi2DeSerializeFMUstate: the state's CRC-32 seal does not match its contents: it was "
                             "edited, truncated or damaged after fmi2SerializeFMUstate wrote it");
        v.pop_back();
        if (v[0] != info().state_magic)
            return in->error("fmi2DeSerializeFMUstate: not a state of this FMU (" + info().model_identifier + ")");
        if (v[1] != info().state_version)
            return in->error("fmi2DeSerializeFMUstate: state version " + format_value(v[1]) + " is not this " +
                             "binary's version " + format_value(info().state_version));
        if (v[7] != static_cast<double>(v.size() - kHeader))
            return in->error("fmi2DeSerializeFMUstate: truncated state (its header counts " + format_value(v[7]) +
                             " model values, " + std::to_string(v.size() - kHeader) + " follow)");
        if (!is_state(v[2]) || (v[6] != 0.0 && v[6] != 1.0))
            return in->error("fmi2DeSerializeFMUstate: state-machine value " + format_value(v[2]) +
                             " or stop-time flag " + format_value(v[6]) + " is not valid");
        auto saved = std::make_unique<SavedState>();
        saved->state = static_cast<unsigned>(v[2]);
        saved->time = v[3];
        saved->start_time = v[4];
        saved->stop_time = v[5];
        saved->stop_time_defined = v[6] != 0.0;
        saved->model.assign(v.begin() + kHeader, v.end());
        const std::string problem = state_problem(*saved);
        if (!problem.empty()) return in->error("fmi2DeSerializeFMUstate: the state does not fit this model: " + problem);
        delete static_cast<SavedState*>(*FMUstate);
        *FMUstate = saved.release();
        return fmi2OK;
    });
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference[], size_t,
                                        const fmi2ValueReference[], size_t, const fmi2Real[], fmi2Real[]) {
    auto* in = static_cast<Instance*>(c);
    if (!in) return fmi2Error;
    return in->error("fmi2GetDirectionalDerivative: not provided (providesDirectionalDerivative is false)");
}

// ---- Co-Simulation --------------------------------------------------------

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t, const fmi2Integer[],
                                       const fmi2Real[]) {
    auto* in = static_cast<Instance*>(c);
    if (!in) return fmi2Error;
    return in->error("fmi2SetRealInputDerivatives: not supported (canInterpolateInputs is false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t, const fmi2Integer[],
                                        fmi2Real[]) {
    auto* in = static_cast<Instance*>(c);
    if (!in) return fmi2Error;
    return in->error("fmi2GetRealOutputDerivatives: not supported (maxOutputDerivativeOrder is 0)");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean /*noSetFMUStatePriorToCurrentPoint*/) {
    auto* in = static_cast<Instance*>(c);
    if (!allowed(in, "fmi2DoStep", kStepComplete)) return fmi2Error;
    const double t = currentCommunicationPoint, h = communicationStepSize;
    if (!std::isfinite(t) || !std::isfinite(h) || h < 0.0)
        return in->error("fmi2DoStep: communication point " + format_value(t) + " with step size " + format_value(h) +
                         " is not a forward step");
    // Masters accumulate communication points in floating point; accept
    // round-off (and re-synchronise to the master's time) but not a jump.
    // Relative to the time only: a long step must not widen it.
    const double tolerance = 1e-9 * std::max(1.0, std::fabs(t));
    if (std::fabs(t - in->time) > tolerance)
        return in->error("fmi2DoStep: expected communication point " + format_value(in->time) + " but got " +
                         format_value(t));
    if (in->stop_time_defined && t + h > in->stop_time + 1e-9 * std::max(1.0, std::fabs(in->stop_time)))
        return in->error("fmi2DoStep: the step to " + format_value(t + h) + " goes past stopTime " +
                         format_value(in->stop_time));
    return guarded(in, "fmi2DoStep", [&] {
        const fmi2Status s = to_fmi(in, in->model->do_step(t, h));
        if (s != fmi2Error) in->time = t + h;
        return s;
    });
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    auto* in = static_cast<Instance*>(c);
    if (!in) return fmi2Error;
    return in->error("fmi2CancelStep: doStep never runs asynchronously, there is nothing to cancel");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
    return report_status(c, "fmi2GetStatus", s, value);
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
    return report_status(c, "fmi2GetRealStatus", s, value, fmi2LastSuccessfulTime,
                         [](const Instance& in) { return fmi2Real{in.time}; });
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value) {
    return report_status(c, "fmi2GetIntegerStatus", s, value);
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
    return report_status(c, "fmi2GetBooleanStatus", s, value, fmi2Terminated,
                         [](const Instance&) { return fmi2Boolean{fmi2False}; });
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
    return report_status(c, "fmi2GetStringStatus", s, value);
}

}  // extern "C"
