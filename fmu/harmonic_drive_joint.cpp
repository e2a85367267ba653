// HarmonicDriveJoint.fmu: the joint itself (motor, harmonic drive, link with
// gravity) for reference trajectories and system simulation. Its variables
// are declared in src/hdjoint/plant_signals.def and parameter_table.def.
// Co-Simulation steps the plant with its own integrator (JointPlant::advance);
// Model Exchange hands a solver the same right-hand side
// (JointPlant::derivative) on the states of HDJ_PLANT_STATES.
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "hdjoint/joint_plant.h"
#include "table_model.h"

namespace hdjoint::fmu {

namespace {

struct StateRow {
    const char* name;
    const char* unit;
    const char* derivative_unit;
    double nominal;
    const char* outputs;  // computed from this state
    const char* description;
};
#define HDJ_STATE_ROW(name, unit, derivative_unit, nominal, outputs, description) \
    {#name, unit, derivative_unit, nominal, outputs, description},
constexpr StateRow kStates[] = {HDJ_PLANT_STATES(HDJ_STATE_ROW)};
#undef HDJ_STATE_ROW
constexpr unsigned kStateCount = sizeof kStates / sizeof kStates[0];
static_assert(kStateCount == kPlantStates, "HDJ_PLANT_STATES lists JointPlant's full state");

struct IndicatorRow {
    const char* name;
    const char* unit;
    const char* description;
};
#define HDJ_INDICATOR_ROW(name, unit, description) {#name, unit, description},
constexpr IndicatorRow kIndicators[] = {HDJ_PLANT_EVENT_INDICATORS(HDJ_INDICATOR_ROW)};
#undef HDJ_INDICATOR_ROW
constexpr unsigned kIndicatorCount = sizeof kIndicators / sizeof kIndicators[0];
static_assert(kIndicatorCount == JointPlant::kEventIndicators, "HDJ_PLANT_EVENT_INDICATORS lists the plant's");
constexpr unsigned kFirstIndicatorReference = 500;

class JointModel final : public TableModel<Parameters, PlantInputs, PlantOutputs, JointPlant> {
public:
    JointModel()
        : TableModel(plant_signals(), [](const Parameters& p) { return validate(p, false, true); }) {}

    double get(unsigned vr) const override {
        if (core_ && vr >= kFirstStateReference && vr < kFirstStateReference + kStateCount)
            return core_->full_state()(vr - kFirstStateReference);
        if (core_ && vr >= kFirstDerivativeReference && vr < kFirstDerivativeReference + kStateCount) {
            PlantFullState dx;
            return core_->derivative(core_->full_state(), core_->time(), in_, &dx, nullptr)
                       ? dx(vr - kFirstDerivativeReference) : std::nan("");
        }
        if (core_ && vr >= kFirstIndicatorReference && vr < kFirstIndicatorReference + kIndicatorCount)
            return core_->event_indicators()(vr - kFirstIndicatorReference);
        return TableModel::get(vr);
    }

    // ---- Model Exchange: the solver's time and states go into the plant, and
    // the outputs follow them at once.
    Result set_time(double since_start) override {
        core_->set_time(since_start);
        return Result::ok();
    }
    Result get_states(double* x) const override {
        const PlantFullState s = core_->full_state();
        for (unsigned i = 0; i < kStateCount; ++i) x[i] = s(i);
        return Result::ok();
    }
    // A state outside the joint's physical range (JointPlant::physical) is
    // refused as Co-Simulation refuses the input that would lead there.
    Result set_states(const double* x) override {
        const PlantFullState s = Eigen::Map<const PlantFullState>(x);
        if (auto problem = outside(s)) return Result::error(*problem);
        core_->set_full_state(s);
        out_ = core_->outputs();
        return Result::ok();
    }
    Result derivatives(double* dx) const override {
        PlantFullState d;
        if (auto problem = outside(core_->full_state())) return Result::error(*problem);
        if (!core_->derivative(core_->full_state(), core_->time(), in_, &d, nullptr))
            return Result::error("the derivative is not finite at theta_m = " + format(core_->state()(0)) + " rad");
        for (unsigned i = 0; i < kStateCount; ++i) dx[i] = d(i);
        return Result::ok();
    }
    Result event_indicators(double* z) const override {
        const Vector<kIndicatorCount> v = core_->event_indicators();
        for (unsigned i = 0; i < kIndicatorCount; ++i) z[i] = v(i);
        return Result::ok();
    }
    void nominals(double* x) const override {
        for (unsigned i = 0; i < kStateCount; ++i) x[i] = kStates[i].nominal;
    }

private:
    static std::string format(double v) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.9g", v);
        return buf;
    }
    // Why the state is outside the joint's physical range, or nothing.
    std::optional<std::string> outside(const PlantFullState& s) const {
        double elastic = 0.0;
        if (core_->physical(s, &elastic)) return std::nullopt;
        if (!s.allFinite()) return std::string("a state is not finite");
        return "the state is outside the joint's physical range: its elastic torsion " + format(elastic) +
               " rad (theta_m = " + format(s(0)) + " rad, theta_l = " + format(s(2)) +
               " rad) is beyond the flexspline's asymptote, where no torque explains it (singular torsion, as "
               "Co-Simulation reports for the same input)";
    }

    Result start() override {
        std::string message;
        return core_->initialize(in_.tau_ext, &message) ? Result::ok() : Result::error(message);
    }
    Result step(double, double h) override {
        std::string message;
        return core_->advance(h, in_, &message) ? Result::ok() : Result::error(message);
    }
};

// The table's variables, then Model Exchange's: the states (300, ...), their
// derivatives (400, ...) and the event indicators (500, ...), all local.
ModelInfo with_model_exchange(ModelInfo info) {
    constexpr double inf = 1e300;
    for (unsigned i = 0; i < kStateCount; ++i)
        info.variables.push_back({kStates[i].name, kFirstStateReference + i, Causality::Local, kStates[i].unit,
                                  std::string("continuous state: ") + kStates[i].description, 0.0, -inf, inf,
                                  "tau_ext", -1, ""});  // the equilibrium it starts from carries tau_ext
    for (unsigned i = 0; i < kStateCount; ++i)
        info.variables.push_back({std::string("der(") + kStates[i].name + ")", kFirstDerivativeReference + i,
                                  Causality::Local, kStates[i].derivative_unit,
                                  std::string("derivative of ") + kStates[i].name, 0.0, -inf, inf, "i_m tau_ext",
                                  static_cast<long>(kFirstStateReference + i), ""});
    for (unsigned i = 0; i < kIndicatorCount; ++i)
        info.variables.push_back({kIndicators[i].name, kFirstIndicatorReference + i, Causality::Local,
                                  kIndicators[i].unit, std::string("event indicator: ") + kIndicators[i].description,
                                  0.0, -inf, inf, "", -1, ""});
    // Each output's states, from the rows that name it.
    for (Variable& v : info.variables) {
        if (v.causality != Causality::Output) continue;
        for (const StateRow& row : kStates) {
            const std::string outputs = std::string(" ") + row.outputs + " ";
            if (outputs.find(" " + v.name + " ") != std::string::npos)
                v.state_dependencies += (v.state_dependencies.empty() ? "" : " ") + std::string(row.name);
        }
    }
    info.continuous_states = kStateCount;
    info.event_indicators = kIndicatorCount;
    return info;
}

}  // namespace

const ModelInfo& this_model() {
    static const ModelInfo info = with_model_exchange(describe_model<JointModel>(
        HDJ_PLANT_FMU, [](const ParameterInfo& row) { return in_plant(row.scope); }));
    return info;
}

}  // namespace hdjoint::fmu
