#pragma once
// What each FMU provides to the shared FMI glue: its identity, a table of
// variables (declared once; the modelDescription is generated from it) and
// a Model object behind them. Nothing here includes FMI headers.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace hdjoint::fmu {

// Local: a variable the glue computes and shows (Model Exchange's states and derivatives).
enum class Causality { Parameter, Input, Output, Local };

struct Variable {
    std::string name;
    unsigned value_reference;
    Causality causality;
    std::string unit;
    std::string description;
    double start;  // parameters and inputs; outputs are calculated
    double min = -1e300, max = 1e300;
    // Outputs: the inputs (space-separated names) the value at initialisation depends on.
    std::string initial_dependencies;
    // Model Exchange: a state derivative's state (its value reference), or -1.
    long derivative_of = -1;
    // Model Exchange outputs: the states (space-separated names) the value depends on.
    std::string state_dependencies;
};

// Model Exchange's states and their derivatives (Local variables).
constexpr unsigned kFirstStateReference = 300;
constexpr unsigned kFirstDerivativeReference = 400;
// FMI 3.0's independent variable, time (FMI 2.0 has none: time is implicit).
constexpr unsigned kTimeReference = 1000;

enum class Status { Ok, Warning, Error };

struct Result {
    Status status = Status::Ok;
    std::string message;
    static Result ok() { return {}; }
    static Result warning(std::string m) { return {Status::Warning, std::move(m)}; }
    static Result error(std::string m) { return {Status::Error, std::move(m)}; }
};

class Model {
public:
    virtual ~Model() = default;
    virtual double get(unsigned vr) const = 0;
    // Inputs and parameters; the glue has already checked the value reference,
    // its causality and the FMI state.
    virtual Result set(unsigned vr, double value) = 0;
    // Leaving initialisation: check parameters, build the model.
    virtual Result initialize(double start_time) = 0;
    // One communication step [t, t+h).
    virtual Result do_step(double t, double h) = 0;
    // Back to the state after instantiation (default parameters, no history).
    virtual void reset() = 0;
    // True once initialize() has built the model (doStep needs it).
    virtual bool initialized() const = 0;
    // Everything the instance holds, as doubles (for FMU state get/set/serialise);
    // load() checks every value and leaves the model as it was when one is wrong.
    virtual std::vector<double> save() const = 0;
    virtual Result load(const std::vector<double>& data) = 0;

    // Model Exchange, for a model with continuous states (ModelInfo::
    // continuous_states > 0; the default is none). Times are since the start
    // (the cores keep their own clock from 0). The glue has checked the state
    // machine, the array sizes and that the model is initialised.
    virtual Result set_time(double /*since_start*/) { return no_states(); }
    virtual Result get_states(double* /*x*/) const { return no_states(); }
    virtual Result set_states(const double* /*x*/) { return no_states(); }
    virtual Result derivatives(double* /*dx*/) const { return no_states(); }
    virtual Result event_indicators(double* /*z*/) const { return no_states(); }
    virtual void nominals(double* /*x*/) const {}

private:
    static Result no_states() { return Result::error("this model has no continuous states (Co-Simulation only)"); }
};

struct ModelInfo {
    std::string model_name;
    std::string model_identifier;
    // Marks this FMU's serialised states (each hdjoint FMU has its own) and
    // their layout: raise state_version whenever the saved fields change.
    double state_magic;
    double state_version;
    std::string description;
    std::vector<Variable> variables;
    std::unique_ptr<Model> (*create)();
    // Model Exchange: the continuous states and event indicators (0: Co-Simulation
    // only). The states are the Local variables from kFirstStateReference on,
    // their derivatives those from kFirstDerivativeReference on, in order.
    std::size_t continuous_states = 0;
    std::size_t event_indicators = 0;
    bool model_exchange() const { return continuous_states > 0; }
};

// Defined once per FMU (in the FMU's own file): the glue and the
// modelDescription generator both take the model from here.
const ModelInfo& this_model();

const Variable* find_variable(const ModelInfo& info, unsigned vr);

}  // namespace hdjoint::fmu
