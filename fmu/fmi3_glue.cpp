// The FMI 3.0 interface, once for every hdjoint FMU: Co-Simulation for all,
// Model Exchange for a model with continuous states (HarmonicDriveJoint).
// Each function names the states it may be called in (FMI 3.0, section 2.3
// and the state machines of 3.2 and 4.2); the work is done by the
// version-independent Instance (instance.h) that fmi2_glue.cpp uses too, so
// both versions check, compute and save alike. Exceptions never cross the C
// boundary: they become fmi3Error and a logged message.
//
// Not provided, and refused with a message naming the capability: event mode
// and early return in Co-Simulation (hasEventMode is false: every step runs
// to its end), intermediate update, clocks and Scheduled Execution,
// directional and adjoint derivatives, output derivatives, structural
// parameters (so no Configuration Mode), per-element dependencies.
#include <string>

#include "description.h"
#include "fmi3Functions.h"
#include "instance.h"
#include "model.h"

namespace {

using hdjoint::fmu::Code;
using hdjoint::fmu::Instance;
using hdjoint::fmu::SavedState;

static_assert(hdjoint::fmu::has_shared_codes(fmi3OK, fmi3Warning, fmi3Discard, fmi3Error),
              "the shared status codes are fmi3Status's");

// FMI 3.0's states: Co-Simulation without event mode (section 4.2) and Model
// Exchange (3.2); kError: after fmi3Error, until fmi3Reset.
using namespace hdjoint::fmu::states;
constexpr unsigned kAny = kInstantiated | kInitializationMode | kEventMode | kContinuousTimeMode | kStepMode |
                          kTerminated | kError;
constexpr unsigned kCanGet = kAny;
constexpr unsigned kCanSet = kInstantiated | kInitializationMode | kEventMode | kContinuousTimeMode | kStepMode;
constexpr unsigned kCanSetParameters = kInstantiated | kInitializationMode;
constexpr unsigned kCanTerminate = kEventMode | kContinuousTimeMode | kStepMode;
// fmi3GetContinuousStates, ...Derivatives, ...EventIndicators, ...Nominals.
constexpr unsigned kCanGetVectors = kInitializationMode | kEventMode | kContinuousTimeMode | kTerminated;

// Each interface its own machine: a state saved by one is refused by the other.
const hdjoint::fmu::StateMachine kCoSimulation = {
    {{kInstantiated, "Instantiated"},
     {kInitializationMode, "Initialization Mode"},
     {kStepMode, "Step Mode"},
     {kTerminated, "Terminated"},
     {kError, "error"}},
    kInstantiated,
    kError,
    kStepMode | kTerminated,
    kInstantiated | kInitializationMode,
    -1.0,
    false,
};
const hdjoint::fmu::StateMachine kModelExchange = {
    {{kInstantiated, "Instantiated"},
     {kInitializationMode, "Initialization Mode"},
     {kEventMode, "Event Mode"},
     {kContinuousTimeMode, "Continuous-Time Mode"},
     {kTerminated, "Terminated"},
     {kError, "error"}},
    kInstantiated,
    kError,
    kEventMode | kContinuousTimeMode | kTerminated,
    kInstantiated | kInitializationMode,
    -1.0,
    true,
};

const hdjoint::fmu::ModelInfo& info() { return hdjoint::fmu::this_model(); }

fmi3Status status(Code c) { return static_cast<fmi3Status>(c); }

Instance* as_instance(fmi3Instance c) { return static_cast<Instance*>(c); }

// The instance, if the Model Exchange (or Co-Simulation) function `function`
// may be called in its state.
Instance* in_state(fmi3Instance c, const char* function, unsigned states, bool model_exchange) {
    Instance* in = static_cast<Instance*>(c);
    return in && in->allowed(function, states, model_exchange) ? in : nullptr;
}
constexpr bool kME = true, kCS = false;

// The instance, if `function` may be called in its state.
Instance* in_state(fmi3Instance c, const char* function, unsigned states) {
    Instance* in = as_instance(c);
    return in && in->allowed(function, states) ? in : nullptr;
}

SavedState* saved(fmi3FMUState s) { return static_cast<SavedState*>(s); }
SavedState** handle(fmi3FMUState* s) { return reinterpret_cast<SavedState**>(s); }

// A call this FMU does not provide: an error, in any state.
fmi3Status not_provided(fmi3Instance c, const std::string& message) {
    Instance* in = as_instance(c);
    return in ? status(in->error(message)) : fmi3Error;
}

// Every variable is a scalar: as many values as value references.
bool scalars(Instance* in, const char* function, size_t nvr, size_t nValues) {
    if (nvr == nValues) return true;
    in->error(std::string(function) + ": " + std::to_string(nValues) + " values for " + std::to_string(nvr) +
              " value references (every variable is a scalar)");
    return false;
}

bool is_model_exchange(const Instance* in) { return &in->machine == &kModelExchange; }

void set_flag(fmi3Boolean* flag, bool value) {
    if (flag) *flag = value ? fmi3True : fmi3False;
}

fmi3Instance instantiate(const char* function, fmi3String instanceName, fmi3String instantiationToken,
                         fmi3Boolean loggingOn, fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage,
                         const hdjoint::fmu::StateMachine& machine, const std::string& refusal) {
    auto refuse = [&](const std::string& message) -> fmi3Instance {
        if (logMessage) logMessage(env, fmi3Error, "logStatusError", (std::string(function) + ": " + message).c_str());
        return nullptr;
    };
    try {
        if (const std::string problem = hdjoint::fmu::instance_name_problem(instanceName); !problem.empty())
            return refuse(problem);
        if (!refusal.empty()) return refuse(refusal);
        const std::string expected = hdjoint::fmu::guid(info());
        if (!instantiationToken || expected != instantiationToken)
            return refuse(std::string("instantiationToken ") + (instantiationToken ? instantiationToken : "(null)") +
                          " does not match this binary's " + expected);
        Instance::Logger log;
        if (logMessage)
            log = [logMessage, env](Code s, const char* category, const std::string& message) {
                logMessage(env, static_cast<fmi3Status>(s), category, message.c_str());
            };
        auto* instance = new Instance(machine, instanceName, log, loggingOn != fmi3False);
        instance->time_is_variable = true;
        return instance;
    } catch (const std::exception& e) {
        return refuse(e.what());
    }
}

}  // namespace

extern "C" {

const char* fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    Instance* in = as_instance(c);
    return in ? status(in->set_debug_logging("fmi3SetDebugLogging", loggingOn != fmi3False, nCategories, categories))
              : fmi3Error;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String /*resourcePath*/, fmi3Boolean /*visible*/,
                                          fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    const std::string refusal =
        info().model_exchange() ? "" : info().model_identifier + " supports Co-Simulation only";
    return instantiate("fmi3InstantiateModelExchange", instanceName, instantiationToken, loggingOn,
                       instanceEnvironment, logMessage, kModelExchange, refusal);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String /*resourcePath*/, fmi3Boolean /*visible*/,
                                         fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean /*earlyReturnAllowed: never returns early*/,
                                         const fmi3ValueReference /*requiredIntermediateVariables*/[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback /*intermediateUpdate*/) {
    std::string refusal;
    if (eventModeUsed != fmi3False) refusal = "eventModeUsed: this FMU has no event mode (hasEventMode is false)";
    else if (nRequiredIntermediateVariables > 0)
        refusal = "requiredIntermediateVariables: this FMU provides no intermediate update";
    return instantiate("fmi3InstantiateCoSimulation", instanceName, instantiationToken, loggingOn,
                       instanceEnvironment, logMessage, kCoSimulation, refusal);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String, fmi3String, fmi3String, fmi3Boolean, fmi3Boolean,
                                               fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback, fmi3LockPreemptionCallback,
                                               fmi3UnlockPreemptionCallback) {
    if (logMessage)
        logMessage(env, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: this FMU supports no Scheduled Execution");
    return nullptr;
}

void fmi3FreeInstance(fmi3Instance c) { delete as_instance(c); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean /*toleranceDefined*/, fmi3Float64 /*tolerance*/,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    Instance* in = in_state(c, "fmi3EnterInitializationMode", kInstantiated);
    if (!in) return fmi3Error;
    const Code s = in->setup_experiment("fmi3EnterInitializationMode", startTime, stopTimeDefined != fmi3False, stopTime);
    if (s == hdjoint::fmu::kOk) in->state = kInitializationMode;
    return status(s);
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c) {
    Instance* in = in_state(c, "fmi3ExitInitializationMode", kInitializationMode);
    if (!in) return fmi3Error;
    return status(in->initialize("fmi3ExitInitializationMode", is_model_exchange(in) ? kEventMode : kStepMode));
}

fmi3Status fmi3EnterEventMode(fmi3Instance c) {
    Instance* in = in_state(c, "fmi3EnterEventMode", kContinuousTimeMode, kME);
    if (!in) return fmi3Error;
    in->state = kEventMode;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance c) {
    Instance* in = as_instance(c);
    return in ? status(in->transition("fmi3Terminate", kCanTerminate, kTerminated)) : fmi3Error;
}

fmi3Status fmi3Reset(fmi3Instance c) {
    Instance* in = as_instance(c);
    return in ? status(in->reset("fmi3Reset")) : fmi3Error;
}

// ---- variables ----------------------------------------------------------------

fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues) {
    Instance* in = in_state(c, "fmi3GetFloat64", kCanGet);
    if (!in || !scalars(in, "fmi3GetFloat64", nvr, nValues)) return fmi3Error;
    return status(in->get_reals("fmi3GetFloat64", vr, nvr, values));
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 values[],
                          size_t nValues) {
    Instance* in = in_state(c, "fmi3SetFloat64", kCanSet);
    if (!in || !scalars(in, "fmi3SetFloat64", nvr, nValues)) return fmi3Error;
    return status(in->set_reals("fmi3SetFloat64", vr, nvr, values, kCanSetParameters));
}

// Every other type: legal calls, but this FMU has no such variables.
#define HDJ_FMI3_NO_VARIABLES(Type, States)                                                                \
    fmi3Status fmi3Get##Type(fmi3Instance c, const fmi3ValueReference[], size_t nvr, fmi3##Type[], size_t) { \
        Instance* in = as_instance(c);                                                                   \
        return in ? status(in->no_such_variables("fmi3Get" #Type, kCanGet, nvr, #Type)) : fmi3Error;     \
    }                                                                                                    \
    fmi3Status fmi3Set##Type(fmi3Instance c, const fmi3ValueReference[], size_t nvr, const fmi3##Type[],  \
                             size_t) {                                                                   \
        Instance* in = as_instance(c);                                                                   \
        return in ? status(in->no_such_variables("fmi3Set" #Type, States, nvr, #Type)) : fmi3Error;      \
    }
HDJ_FMI3_NO_VARIABLES(Float32, kCanSet)
HDJ_FMI3_NO_VARIABLES(Int8, kCanSet)
HDJ_FMI3_NO_VARIABLES(UInt8, kCanSet)
HDJ_FMI3_NO_VARIABLES(Int16, kCanSet)
HDJ_FMI3_NO_VARIABLES(UInt16, kCanSet)
HDJ_FMI3_NO_VARIABLES(Int32, kCanSet)
HDJ_FMI3_NO_VARIABLES(UInt32, kCanSet)
HDJ_FMI3_NO_VARIABLES(Int64, kCanSet)
HDJ_FMI3_NO_VARIABLES(UInt64, kCanSet)
HDJ_FMI3_NO_VARIABLES(Boolean, kCanSet)
HDJ_FMI3_NO_VARIABLES(String, kCanSet)
#undef HDJ_FMI3_NO_VARIABLES

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference[], size_t nvr, size_t[], fmi3Binary[], size_t) {
    Instance* in = as_instance(c);
    return in ? status(in->no_such_variables("fmi3GetBinary", kCanGet, nvr, "Binary")) : fmi3Error;
}
fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference[], size_t nvr, const size_t[], const fmi3Binary[],
                         size_t) {
    Instance* in = as_instance(c);
    return in ? status(in->no_such_variables("fmi3SetBinary", kCanSet, nvr, "Binary")) : fmi3Error;
}
fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference[], size_t nvr, fmi3Clock[]) {
    Instance* in = as_instance(c);
    return in ? status(in->no_such_variables("fmi3GetClock", kCanGet, nvr, "Clock")) : fmi3Error;
}
fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference[], size_t nvr, const fmi3Clock[]) {
    Instance* in = as_instance(c);
    return in ? status(in->no_such_variables("fmi3SetClock", kCanSet, nvr, "Clock")) : fmi3Error;
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference, size_t*) {
    return not_provided(c, "fmi3GetNumberOfVariableDependencies: not provided (the dependencies are in "
                           "modelDescription.xml; providesPerElementDependencies is false)");
}
fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference, size_t[], fmi3ValueReference[], size_t[],
                                       fmi3DependencyKind[], size_t) {
    return not_provided(c, "fmi3GetVariableDependencies: not provided (the dependencies are in "
                           "modelDescription.xml; providesPerElementDependencies is false)");
}

// ---- FMU state ------------------------------------------------------------------

fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState* FMUState) {
    Instance* in = as_instance(c);
    return in ? status(in->get_state("fmi3GetFMUState", handle(FMUState))) : fmi3Error;
}
fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState FMUState) {
    Instance* in = as_instance(c);
    return in ? status(in->set_state("fmi3SetFMUState", saved(FMUState))) : fmi3Error;
}
fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState* FMUState) {
    Instance* in = as_instance(c);
    return in ? status(in->free_state("fmi3FreeFMUState", handle(FMUState))) : fmi3Error;
}
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState FMUState, size_t* size) {
    Instance* in = as_instance(c);
    return in ? status(in->serialized_size("fmi3SerializedFMUStateSize", saved(FMUState), size)) : fmi3Error;
}
fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    Instance* in = as_instance(c);
    return in ? status(in->serialize("fmi3SerializeFMUState", saved(FMUState), serializedState, size)) : fmi3Error;
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState* FMUState) {
    Instance* in = as_instance(c);
    return in ? status(in->deserialize("fmi3DeserializeFMUState", serializedState, size, handle(FMUState)))
              : fmi3Error;
}

// ---- not provided -----------------------------------------------------------------

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference[], size_t,
                                        const fmi3ValueReference[], size_t, const fmi3Float64[], size_t,
                                        fmi3Float64[], size_t) {
    return not_provided(c, "fmi3GetDirectionalDerivative: not provided (providesDirectionalDerivatives is false)");
}
fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3ValueReference[],
                                    size_t, const fmi3Float64[], size_t, fmi3Float64[], size_t) {
    return not_provided(c, "fmi3GetAdjointDerivative: not provided (providesAdjointDerivatives is false)");
}
fmi3Status fmi3EnterConfigurationMode(fmi3Instance c) {
    return not_provided(c, "fmi3EnterConfigurationMode: this FMU has no structural parameters");
}
fmi3Status fmi3ExitConfigurationMode(fmi3Instance c) {
    return not_provided(c, "fmi3ExitConfigurationMode: this FMU has no structural parameters");
}

#define HDJ_FMI3_NO_CLOCKS(Function, ...)                                                  \
    fmi3Status Function(fmi3Instance c, __VA_ARGS__) {                                     \
        return not_provided(c, #Function ": this FMU has no clocks");                      \
    }
HDJ_FMI3_NO_CLOCKS(fmi3GetIntervalDecimal, const fmi3ValueReference[], size_t, fmi3Float64[], fmi3IntervalQualifier[])
HDJ_FMI3_NO_CLOCKS(fmi3GetIntervalFraction, const fmi3ValueReference[], size_t, fmi3UInt64[], fmi3UInt64[],
                   fmi3IntervalQualifier[])
HDJ_FMI3_NO_CLOCKS(fmi3GetShiftDecimal, const fmi3ValueReference[], size_t, fmi3Float64[])
HDJ_FMI3_NO_CLOCKS(fmi3GetShiftFraction, const fmi3ValueReference[], size_t, fmi3UInt64[], fmi3UInt64[])
HDJ_FMI3_NO_CLOCKS(fmi3SetIntervalDecimal, const fmi3ValueReference[], size_t, const fmi3Float64[])
HDJ_FMI3_NO_CLOCKS(fmi3SetIntervalFraction, const fmi3ValueReference[], size_t, const fmi3UInt64[],
                   const fmi3UInt64[])
HDJ_FMI3_NO_CLOCKS(fmi3SetShiftDecimal, const fmi3ValueReference[], size_t, const fmi3Float64[])
HDJ_FMI3_NO_CLOCKS(fmi3SetShiftFraction, const fmi3ValueReference[], size_t, const fmi3UInt64[], const fmi3UInt64[])
HDJ_FMI3_NO_CLOCKS(fmi3ActivateModelPartition, fmi3ValueReference, fmi3Float64)
#undef HDJ_FMI3_NO_CLOCKS

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c) {
    return not_provided(c, "fmi3EvaluateDiscreteStates: this FMU has no clocks");
}

// ---- Model Exchange and event mode --------------------------------------------------

// No discrete states: an event (a state event of the event indicators)
// changes nothing but lets the solver restart at the kink.
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean* discreteStatesNeedUpdate,
                                    fmi3Boolean* terminateSimulation, fmi3Boolean* nominalsOfContinuousStatesChanged,
                                    fmi3Boolean* valuesOfContinuousStatesChanged, fmi3Boolean* nextEventTimeDefined,
                                    fmi3Float64* nextEventTime) {
    if (!in_state(c, "fmi3UpdateDiscreteStates", kEventMode, kME)) return fmi3Error;
    for (fmi3Boolean* flag : {discreteStatesNeedUpdate, terminateSimulation, nominalsOfContinuousStatesChanged,
                              valuesOfContinuousStatesChanged, nextEventTimeDefined})
        set_flag(flag, false);
    if (nextEventTime) *nextEventTime = 0.0;
    return fmi3OK;
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) {
    Instance* in = in_state(c, "fmi3EnterContinuousTimeMode", kEventMode, kME);
    if (!in) return fmi3Error;
    in->state = kContinuousTimeMode;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean /*noSetFMUStatePriorToCurrentPoint*/,
                                       fmi3Boolean* enterEventMode, fmi3Boolean* terminateSimulation) {
    if (!in_state(c, "fmi3CompletedIntegratorStep", kContinuousTimeMode, kME)) return fmi3Error;
    set_flag(enterEventMode, false);
    set_flag(terminateSimulation, false);
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 time) {
    Instance* in = in_state(c, "fmi3SetTime", kEventMode | kContinuousTimeMode, kME);
    return in ? status(in->set_time("fmi3SetTime", time)) : fmi3Error;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 x[], size_t n) {
    Instance* in = in_state(c, "fmi3SetContinuousStates", kContinuousTimeMode, kME);
    return in ? status(in->set_states("fmi3SetContinuousStates", x, n)) : fmi3Error;
}

#define HDJ_FMI3_VECTOR(Function, Which, States)                                                                 \
    fmi3Status Function(fmi3Instance c, fmi3Float64 values[], size_t n) {                                 \
        Instance* in = in_state(c, #Function, States, kME);                                                    \
        return in ? status(in->get_vector(#Function, Instance::Vector::Which, values, n)) : fmi3Error;    \
    }
HDJ_FMI3_VECTOR(fmi3GetContinuousStateDerivatives, Derivatives, kCanGetVectors)
HDJ_FMI3_VECTOR(fmi3GetEventIndicators, EventIndicators, kCanGetVectors)
HDJ_FMI3_VECTOR(fmi3GetContinuousStates, States, kCanGetVectors)
// The nominals are fixed: known from instantiation on.
HDJ_FMI3_VECTOR(fmi3GetNominalsOfContinuousStates, Nominals, kCanGetVectors | kInstantiated)
#undef HDJ_FMI3_VECTOR

// Model Exchange functions (FMI 3.0, 3.2.1): a Co-Simulation instance refuses them.
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t* n) {
    Instance* in = in_state(c, "fmi3GetNumberOfEventIndicators", kAny, kME);
    if (!in) return fmi3Error;
    if (!n) return status(in->error("fmi3GetNumberOfEventIndicators: null argument"));
    *n = info().event_indicators;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t* n) {
    Instance* in = in_state(c, "fmi3GetNumberOfContinuousStates", kAny, kME);
    if (!in) return fmi3Error;
    if (!n) return status(in->error("fmi3GetNumberOfContinuousStates: null argument"));
    *n = info().continuous_states;
    return fmi3OK;
}

// ---- Co-Simulation ------------------------------------------------------------------

fmi3Status fmi3EnterStepMode(fmi3Instance c) {
    return not_provided(c, "fmi3EnterStepMode: this FMU has no event mode (hasEventMode is false): "
                           "fmi3ExitInitializationMode enters Step Mode");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3Int32[],
                                    fmi3Float64[], size_t) {
    return not_provided(c, "fmi3GetOutputDerivatives: not provided (maxOutputDerivativeOrder is 0)");
}

// Every step runs to its end (no early return, no event to hand back).
fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean /*noSetFMUStatePriorToCurrentPoint*/, fmi3Boolean* eventHandlingNeeded,
                      fmi3Boolean* terminateSimulation, fmi3Boolean* earlyReturn, fmi3Float64* lastSuccessfulTime) {
    Instance* in = in_state(c, "fmi3DoStep", kStepMode, kCS);
    if (!in) return fmi3Error;
    const Code s = in->do_step("fmi3DoStep", currentCommunicationPoint, communicationStepSize);
    set_flag(eventHandlingNeeded, false);
    set_flag(terminateSimulation, false);
    set_flag(earlyReturn, false);
    if (lastSuccessfulTime) *lastSuccessfulTime = in->time;
    return status(s);
}

}  // extern "C"
