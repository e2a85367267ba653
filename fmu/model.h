#pragma once
// What each FMU provides to the shared FMI glue: its identity, a table of
// variables (declared once; the modelDescription is generated from it) and
// a Model object behind them. Nothing here includes FMI headers.
#include <memory>
#include <string>
#include <vector>

namespace hdjoint::fmu {

enum class Causality { Parameter, Input, Output };

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
};

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
};

// Defined once per FMU (in the FMU's own file): the glue and the
// modelDescription generator both take the model from here.
const ModelInfo& this_model();

const Variable* find_variable(const ModelInfo& info, unsigned vr);

}  // namespace hdjoint::fmu
