#pragma once
// What an FMU instance does whichever FMI version calls it: the state machine
// bookkeeping (a mask of states per call), argument, value and time checks,
// logging, the Model behind the variables, and FMU state copies, serialised
// and sealed. fmi2_glue.cpp and fmi3_glue.cpp are thin translations of their
// standard's C functions onto it; nothing here includes an FMI header.
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "model.h"

namespace hdjoint::fmu {

// Status codes with the values of fmi2Status and fmi3Status (both glues
// static_assert that they agree).
enum Code : int { kOk = 0, kWarning = 1, kDiscard = 2, kError = 3 };
template <class S>
constexpr bool has_shared_codes(S ok, S warning, S discard, S error) {
    return static_cast<int>(ok) == kOk && static_cast<int>(warning) == kWarning &&
           static_cast<int>(discard) == kDiscard && static_cast<int>(error) == kError;
}

// The states of both versions' state machines, as bits, so that each function
// names the set of states it may be called in. FMI 2.0 Co-Simulation's step
// complete is FMI 3.0's Step Mode; step failed is FMI 2.0's only. The values
// are stored in serialised FMU states: never renumber them.
namespace states {
enum State : unsigned {
    kInstantiated = 1u << 0,
    kInitializationMode = 1u << 1,
    kStepComplete = 1u << 2,
    kStepMode = kStepComplete,
    kStepFailed = 1u << 3,
    kTerminated = 1u << 4,
    kError = 1u << 5,
    kEventMode = 1u << 6,           // Model Exchange
    kContinuousTimeMode = 1u << 7,  // Model Exchange
};
}  // namespace states

// One glue's state machine: its states as bits, named, and which of them
// need (or must not have) an initialised model. `error` is the state an
// error leaves the instance in.
struct StateMachine {
    std::vector<std::pair<unsigned, const char*>> states;
    unsigned instantiated;  // the state after instantiation and reset
    unsigned error;
    unsigned needs_model;   // after initialisation: the model is built
    unsigned before_init;   // before it: no model, the time is the start time
    // Marks the serialised states of this glue: the FMU's magic number times
    // this sign, so that neither FMI version loads the other's states.
    double magic_sign;
    // Model Exchange's machine (else Co-Simulation's).
    bool model_exchange;

    const char* name(unsigned state) const;
    bool is_state(double value) const;
    unsigned all() const;
};

// The saved copy behind an FMU state handle.
struct SavedState {
    unsigned state = 0;
    double time = 0.0, start_time = 0.0, stop_time = 0.0;
    bool stop_time_defined = false;
    std::vector<double> model;
};

std::string format_value(double v);

// Why an instance name is refused (null, empty or only whitespace), or "".
std::string instance_name_problem(const char* name);

class Instance {
public:
    using Logger = std::function<void(Code, const char* category, const std::string& message)>;

    Instance(const StateMachine& machine, std::string name, Logger logger, bool debug_logging);

    const StateMachine& machine;
    std::string name;
    Logger logger;
    bool debug_logging;
    unsigned state;
    double time = 0.0, start_time = 0.0, stop_time = 0.0;
    bool stop_time_defined = false;
    // FMI 3.0: the independent variable `time` (kTimeReference) can be read.
    bool time_is_variable = false;
    std::unique_ptr<Model> model;

    void log(Code status, const char* category, const std::string& message) const;
    // Log the error and move to the error state.
    Code error(const std::string& message);
    // Whether `function` may be called in the present state; if not, an error.
    bool allowed(const char* function, unsigned states);
    // The same for a function of one interface only (Model Exchange or Co-Simulation).
    bool allowed(const char* function, unsigned states, bool model_exchange);
    // A call that only moves the state machine.
    Code transition(const char* function, unsigned from, unsigned to);
    Code to_code(const Result& r);
    // The same, the message naming the FMI function.
    Code with_function(const char* function, Result r);

    // Run `body`, turning any exception into an error naming `function`.
    template <class Body>
    Code guarded(const char* function, Body body) {
        try {
            return body();
        } catch (...) {
            return error(std::string(function) + ": " + exception_message());
        }
    }

    Code set_debug_logging(const char* function, bool on, std::size_t n, const char* const categories[]);
    // Experiment times (fmi2SetupExperiment, fmi3EnterInitializationMode).
    Code setup_experiment(const char* function, double start, bool stop_defined, double stop);
    // Build the model from its parameters and go to `next`.
    Code initialize(const char* function, unsigned next);
    Code reset(const char* function);

    Code get_reals(const char* function, const unsigned vr[], std::size_t nvr, double values[]);
    // `parameter_states`: where parameters may still be set.
    Code set_reals(const char* function, const unsigned vr[], std::size_t nvr, const double values[],
                   unsigned parameter_states);
    // Legal in `states`, but this FMU has no variables of `type`.
    Code no_such_variables(const char* function, unsigned states, std::size_t nvr, const char* type);
    // A communication step [t, t+h): checks the point, the size and the stop time.
    Code do_step(const char* function, double t, double h);

    // Model Exchange: the solver sets the time and the continuous states and
    // reads the states, their derivatives, the event indicators and the
    // states' nominal magnitudes. `n` is checked against the model's count.
    Code set_time(const char* function, double t);
    Code set_states(const char* function, const double x[], std::size_t n);
    enum class Vector { States, Derivatives, EventIndicators, Nominals };
    Code get_vector(const char* function, Vector which, double out[], std::size_t n);

    // FMU state: copies, and their serialised, sealed form.
    Code get_state(const char* function, SavedState** handle);
    Code set_state(const char* function, const SavedState* saved);
    Code free_state(const char* function, SavedState** handle);
    Code serialized_size(const char* function, const SavedState* saved, std::size_t* size);
    Code serialize(const char* function, const SavedState* saved, unsigned char* bytes, std::size_t size);
    Code deserialize(const char* function, const unsigned char* bytes, std::size_t size, SavedState** handle);

private:
    static std::string exception_message();
    double magic() const;
    // The common checks of a Model Exchange call that needs the built model.
    Code check_vector(const char* function, const void* array, std::size_t n, std::size_t expected);
    std::vector<double> flatten(const SavedState& s) const;
    std::string state_problem(const SavedState& s) const;
};

}  // namespace hdjoint::fmu
