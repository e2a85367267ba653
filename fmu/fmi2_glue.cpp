// The FMI 2.0 Co-Simulation interface, once for every hdjoint FMU: the FMI
// 2.0 state machine as masks of states per function, translated onto the
// version-independent Instance (instance.h), which owns the checks, logging
// and FMU state copies; the physics is behind the Model of this_model().
// Exceptions never cross the C boundary: they become fmi2Error and a logged
// message.
#include <memory>
#include <string>

#include "description.h"
#include "fmi2Functions.h"
#include "instance.h"
#include "model.h"

namespace {

using hdjoint::fmu::Code;
using hdjoint::fmu::Instance;
using hdjoint::fmu::SavedState;

static_assert(hdjoint::fmu::has_shared_codes(fmi2OK, fmi2Warning, fmi2Discard, fmi2Error),
              "the shared status codes are fmi2Status's");

// FMI 2.0's states: Co-Simulation (section 4.2.4) and Model Exchange (3.2.3).
using namespace hdjoint::fmu::states;
constexpr unsigned kCanGet =
    kInitializationMode | kStepComplete | kStepFailed | kTerminated | kError | kEventMode | kContinuousTimeMode;
constexpr unsigned kCanSet = kInstantiated | kInitializationMode | kStepComplete | kEventMode | kContinuousTimeMode;
// fmi2GetContinuousStates, ...Derivatives, ...EventIndicators, ...NominalsOfContinuousStates.
constexpr unsigned kCanGetVectors = kInitializationMode | kEventMode | kContinuousTimeMode | kTerminated;
// fmi2Get*Status: after a step, not in the error state (FMI 2.0, table in 4.2.4).
constexpr unsigned kCanGetStatus = kStepComplete | kStepFailed | kTerminated;

const hdjoint::fmu::StateMachine kCoSimulation = {
    {{kInstantiated, "instantiated"},
     {kInitializationMode, "initialization mode"},
     {kStepComplete, "step complete"},
     {kStepFailed, "step failed"},
     {kTerminated, "terminated"},
     {kError, "error"}},
    kInstantiated,
    kError,
    kStepComplete | kStepFailed | kTerminated,
    kInstantiated | kInitializationMode,
    1.0,
    false,
};
// Model Exchange's own machine: a state saved by one interface is refused by the other.
const hdjoint::fmu::StateMachine kModelExchange = {
    {{kInstantiated, "instantiated"},
     {kInitializationMode, "initialization mode"},
     {kEventMode, "event mode"},
     {kContinuousTimeMode, "continuous-time mode"},
     {kTerminated, "terminated"},
     {kError, "error"}},
    kInstantiated,
    kError,
    kEventMode | kContinuousTimeMode | kTerminated,
    kInstantiated | kInitializationMode,
    1.0,
    true,
};
bool is_model_exchange(const Instance* in) { return &in->machine == &kModelExchange; }

const hdjoint::fmu::ModelInfo& info() { return hdjoint::fmu::this_model(); }

fmi2Status status(Code c) { return static_cast<fmi2Status>(c); }

// The instance, if the Model Exchange (or Co-Simulation) function `function`
// may be called in its state.
Instance* in_state(fmi2Component c, const char* function, unsigned states, bool model_exchange) {
    Instance* in = static_cast<Instance*>(c);
    return in && in->allowed(function, states, model_exchange) ? in : nullptr;
}
constexpr bool kME = true, kCS = false;

// The instance behind a component, if `function` may be called in its state.
Instance* in_state(fmi2Component c, const char* function, unsigned states) {
    auto* in = static_cast<Instance*>(c);
    return in && in->allowed(function, states) ? in : nullptr;
}

SavedState* saved(fmi2FMUstate s) { return static_cast<SavedState*>(s); }

// A call this FMU does not provide: an error, in any state.
fmi2Status not_provided(fmi2Component c, const std::string& message) {
    auto* in = static_cast<Instance*>(c);
    return in ? status(in->error(message)) : fmi2Error;
}

// An fmi2Get*Status call: after a step (not in the error state), the one
// kind this type reports (`known`, with `answer(instance)`), fmi2Discard for
// any other: doStep is synchronous, so nothing is ever pending.
template <class T>
fmi2Status report_status(fmi2Component c, const char* function, fmi2StatusKind, T*) {
    return in_state(c, function, kCanGetStatus, kCS) ? fmi2Discard : fmi2Error;
}
template <class T, class Answer>
fmi2Status report_status(fmi2Component c, const char* function, fmi2StatusKind asked, T* value,
                         fmi2StatusKind known, Answer answer) {
    Instance* in = in_state(c, function, kCanGetStatus, kCS);
    if (!in) return fmi2Error;
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
    const std::string name = instanceName ? instanceName : "";
    auto refuse = [&](const std::string& message) -> fmi2Component {
        if (logger) logger(env, name.c_str(), fmi2Error, "logStatusError", "%s", message.c_str());
        return nullptr;
    };
    try {
        if (const std::string problem = hdjoint::fmu::instance_name_problem(instanceName); !problem.empty())
            return refuse("fmi2Instantiate: " + problem);
        if (fmuType != fmi2CoSimulation && !(fmuType == fmi2ModelExchange && info().model_exchange()))
            return refuse("fmi2Instantiate: " + info().model_identifier + " supports Co-Simulation only");
        const std::string expected = hdjoint::fmu::guid(info());
        if (!fmuGUID || expected != fmuGUID)
            return refuse(std::string("fmi2Instantiate: GUID ") + (fmuGUID ? fmuGUID : "(null)") +
                          " does not match this binary's " + expected);
        Instance::Logger log;
        if (logger) {
            // The message goes through "%s": the logger formats printf-style.
            log = [logger, env, name](Code s, const char* category, const std::string& message) {
                logger(env, name.c_str(), static_cast<fmi2Status>(s), category, "%s", message.c_str());
            };
        }
        return new Instance(fmuType == fmi2ModelExchange ? kModelExchange : kCoSimulation, name, log,
                            loggingOn != fmi2False);
    } catch (const std::exception& e) {
        return refuse(std::string("fmi2Instantiate: ") + e.what());
    }
}

void fmi2FreeInstance(fmi2Component c) { delete static_cast<Instance*>(c); }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    auto* in = static_cast<Instance*>(c);
    if (!in) return fmi2Error;
    return status(in->set_debug_logging("fmi2SetDebugLogging", loggingOn != fmi2False, nCategories, categories));
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean /*toleranceDefined*/, fmi2Real /*tolerance*/,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Instance* in = in_state(c, "fmi2SetupExperiment", kInstantiated);
    if (!in) return fmi2Error;
    return status(in->setup_experiment("fmi2SetupExperiment", startTime, stopTimeDefined != fmi2False, stopTime));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    auto* in = static_cast<Instance*>(c);
    if (!in) return fmi2Error;
    return status(in->transition("fmi2EnterInitializationMode", kInstantiated, kInitializationMode));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance* in = in_state(c, "fmi2ExitInitializationMode", kInitializationMode);
    if (!in) return fmi2Error;
    return status(in->initialize("fmi2ExitInitializationMode", is_model_exchange(in) ? kEventMode : kStepComplete));
}

// Not in the error state (FMI 2.0, 4.2.4): only after a step (or, in Model
// Exchange, from event or continuous-time mode).
fmi2Status fmi2Terminate(fmi2Component c) {
    auto* in = static_cast<Instance*>(c);
    if (!in) return fmi2Error;
    return status(in->transition("fmi2Terminate", kStepComplete | kStepFailed | kEventMode | kContinuousTimeMode,
                                 kTerminated));
}

fmi2Status fmi2Reset(fmi2Component c) {
    auto* in = static_cast<Instance*>(c);
    return in ? status(in->reset("fmi2Reset")) : fmi2Error;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Instance* in = in_state(c, "fmi2GetReal", kCanGet);
    return in ? status(in->get_reals("fmi2GetReal", vr, nvr, value)) : fmi2Error;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Instance* in = in_state(c, "fmi2SetReal", kCanSet);
    return in ? status(in->set_reals("fmi2SetReal", vr, nvr, value, kInstantiated | kInitializationMode)) : fmi2Error;
}

#define HDJ_FMI2_NO_VARIABLES(Function, Type, Const, States)                                              \
    fmi2Status Function(fmi2Component c, const fmi2ValueReference[], size_t nvr, Const fmi2##Type[]) {  \
        auto* in = static_cast<Instance*>(c);                                                           \
        return in ? status(in->no_such_variables(#Function, States, nvr, #Type)) : fmi2Error;          \
    }
HDJ_FMI2_NO_VARIABLES(fmi2GetInteger, Integer, , kCanGet)
HDJ_FMI2_NO_VARIABLES(fmi2GetBoolean, Boolean, , kCanGet)
HDJ_FMI2_NO_VARIABLES(fmi2GetString, String, , kCanGet)
HDJ_FMI2_NO_VARIABLES(fmi2SetInteger, Integer, const, kCanSet)
HDJ_FMI2_NO_VARIABLES(fmi2SetBoolean, Boolean, const, kCanSet)
HDJ_FMI2_NO_VARIABLES(fmi2SetString, String, const, kCanSet)
#undef HDJ_FMI2_NO_VARIABLES

// ---- FMU state ------------------------------------------------------------

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    auto* in = static_cast<Instance*>(c);
    return in ? status(in->get_state("fmi2GetFMUstate", reinterpret_cast<SavedState**>(FMUstate))) : fmi2Error;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    auto* in = static_cast<Instance*>(c);
    return in ? status(in->set_state("fmi2SetFMUstate", saved(FMUstate))) : fmi2Error;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    auto* in = static_cast<Instance*>(c);
    return in ? status(in->free_state("fmi2FreeFMUstate", reinterpret_cast<SavedState**>(FMUstate))) : fmi2Error;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size) {
    auto* in = static_cast<Instance*>(c);
    return in ? status(in->serialized_size("fmi2SerializedFMUstateSize", saved(FMUstate), size)) : fmi2Error;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    auto* in = static_cast<Instance*>(c);
    return in ? status(in->serialize("fmi2SerializeFMUstate", saved(FMUstate),
                                     reinterpret_cast<unsigned char*>(serializedState), size))
              : fmi2Error;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate* FMUstate) {
    auto* in = static_cast<Instance*>(c);
    return in ? status(in->deserialize("fmi2DeSerializeFMUstate", reinterpret_cast<const unsigned char*>(serializedState),
                                       size, reinterpret_cast<SavedState**>(FMUstate)))
              : fmi2Error;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference[], size_t,
                                        const fmi2ValueReference[], size_t, const fmi2Real[], fmi2Real[]) {
    return not_provided(c, "fmi2GetDirectionalDerivative: not provided (providesDirectionalDerivative is false)");
}

// ---- Model Exchange (HarmonicDriveJoint) ---------------------------------------

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    Instance* in = in_state(c, "fmi2EnterEventMode", kContinuousTimeMode, kME);
    if (!in) return fmi2Error;
    in->state = kEventMode;
    return fmi2OK;
}

// No discrete states: an event (of the event indicators) changes nothing but
// lets the solver restart at the kink.
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo* eventInfo) {
    Instance* in = in_state(c, "fmi2NewDiscreteStates", kEventMode, kME);
    if (!in) return fmi2Error;
    if (!eventInfo) return status(in->error("fmi2NewDiscreteStates: eventInfo is null"));
    *eventInfo = fmi2EventInfo{fmi2False, fmi2False, fmi2False, fmi2False, fmi2False, 0.0};
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    Instance* in = in_state(c, "fmi2EnterContinuousTimeMode", kEventMode, kME);
    if (!in) return fmi2Error;
    in->state = kContinuousTimeMode;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean /*noSetFMUStatePriorToCurrentPoint*/,
                                       fmi2Boolean* enterEventMode, fmi2Boolean* terminateSimulation) {
    if (!in_state(c, "fmi2CompletedIntegratorStep", kContinuousTimeMode, kME)) return fmi2Error;
    if (enterEventMode) *enterEventMode = fmi2False;
    if (terminateSimulation) *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    Instance* in = in_state(c, "fmi2SetTime", kEventMode | kContinuousTimeMode, kME);
    return in ? status(in->set_time("fmi2SetTime", time)) : fmi2Error;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    Instance* in = in_state(c, "fmi2SetContinuousStates", kContinuousTimeMode, kME);
    return in ? status(in->set_states("fmi2SetContinuousStates", x, nx)) : fmi2Error;
}

#define HDJ_FMI2_VECTOR(Function, Which, States)                                                                 \
    fmi2Status Function(fmi2Component c, fmi2Real values[], size_t n) {                                   \
        Instance* in = in_state(c, #Function, States, kME);                                                    \
        return in ? status(in->get_vector(#Function, Instance::Vector::Which, values, n)) : fmi2Error;    \
    }
HDJ_FMI2_VECTOR(fmi2GetDerivatives, Derivatives, kCanGetVectors)
HDJ_FMI2_VECTOR(fmi2GetEventIndicators, EventIndicators, kCanGetVectors)
HDJ_FMI2_VECTOR(fmi2GetContinuousStates, States, kCanGetVectors)
// The nominals are fixed: known from instantiation on.
HDJ_FMI2_VECTOR(fmi2GetNominalsOfContinuousStates, Nominals, kCanGetVectors | kInstantiated)
#undef HDJ_FMI2_VECTOR

// ---- Co-Simulation --------------------------------------------------------

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t, const fmi2Integer[],
                                       const fmi2Real[]) {
    return not_provided(c, "fmi2SetRealInputDerivatives: not supported (canInterpolateInputs is false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t, const fmi2Integer[],
                                        fmi2Real[]) {
    return not_provided(c, "fmi2GetRealOutputDerivatives: not supported (maxOutputDerivativeOrder is 0)");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean /*noSetFMUStatePriorToCurrentPoint*/) {
    Instance* in = in_state(c, "fmi2DoStep", kStepComplete, kCS);
    return in ? status(in->do_step("fmi2DoStep", currentCommunicationPoint, communicationStepSize)) : fmi2Error;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    return not_provided(c, "fmi2CancelStep: doStep never runs asynchronously, there is nothing to cancel");
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
