#pragma once
// The Model of an FMU built from its tables: the parameter table and the
// signal list (src/hdjoint/*_signals.def). get/set, the variables of the
// modelDescription and the FMU state (named, validated fields) are written
// here once for every FMU; an FMU adds only how its core starts and steps.
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "hdjoint/signal_table.h"
#include "hdjoint/state_fields.h"
#include "model.h"
#include "parameter_access.h"

namespace hdjoint::fmu {

constexpr unsigned kFirstInputReference = 100;
constexpr unsigned kFirstOutputReference = 200;

// The FMU variables of a signal table: inputs 100, 101, ...; outputs 200, 201, ...
template <class In, class Out>
std::vector<Variable> signal_variables(const SignalTable<In, Out>& table) {
    constexpr double inf = 1e300;
    std::vector<Variable> vars;
    unsigned next_input = kFirstInputReference, next_output = kFirstOutputReference;
    for (const Signal<In, Out>& s : table) {
        if (s.kind == SignalKind::Input)
            vars.push_back({s.name, next_input++, Causality::Input, s.unit, s.description, 0.0, -inf, inf, "", -1, ""});
        else if (s.kind == SignalKind::Output)
            vars.push_back({s.name, next_output++, Causality::Output, s.unit, s.description, 0.0, -inf, inf,
                            s.initial_dependencies, -1, ""});
    }
    return vars;
}

// The FMU variables of a parameter table: the rows `keep` accepts, value reference = row index.
template <class Params, class Keep>
std::vector<Variable> parameter_variables(Keep keep) {
    std::vector<Variable> vars;
    for (unsigned i = 0; i < ParameterRows<Params>::count(); ++i) {
        const auto& p = ParameterRows<Params>::table()[i];
        if (keep(p))
            vars.push_back({p.name, i, Causality::Parameter, p.unit, p.description, p.default_value, p.min, p.max, "", -1, ""});
    }
    return vars;
}

template <class ParamsType, class In, class Out, class Core>
class TableModel : public Model {
public:
    using Params = ParamsType;
    using Inputs = In;
    using Outputs = Out;

    using Check = std::optional<std::string> (*)(const Params&);

    // `check`: the first problem with a parameter set for this FMU, or nothing.
    TableModel(const SignalTable<In, Out>& signals, Check check) : check_(check), signals_(&signals) {
        for (const Signal<In, Out>& s : signals) {
            if (s.kind == SignalKind::Input) inputs_.push_back(&s);
            if (s.kind == SignalKind::Output) outputs_.push_back(&s);
        }
    }

    double get(unsigned vr) const override {
        if (is_parameter<Params>(vr)) return parameter_value(p_, vr);
        if (const Signal<In, Out>* s = input(vr)) return in_.*(s->input);
        if (const Signal<In, Out>* s = output(vr)) return out_.*(s->output);
        return 0.0;
    }

    Result set(unsigned vr, double value) override {
        if (is_parameter<Params>(vr)) parameter_ref(p_, vr) = value;
        else if (const Signal<In, Out>* s = input(vr)) in_.*(s->input) = value;
        return Result::ok();
    }

    Result initialize(double start_time) override {
        if (auto problem = parameter_problem(p_)) return Result::error(*problem);
        core_ = std::make_unique<Core>(make_core(p_, start_time));
        return with_outputs(start());
    }

    Result do_step(double t, double h) override {
        if (!core_) return Result::error("doStep on a model that was never initialised");
        return with_outputs(step(t, h));
    }

    void reset() override {
        p_ = Params{};
        in_ = In{};
        out_ = Out{};
        core_.reset();
    }


    bool initialized() const override { return core_ != nullptr; }
    std::vector<Variable> signal_variables() const { return fmu::signal_variables(*signals_); }

    std::vector<double> save() const override {
        std::vector<double> d;
        StateWriter w(&d);
        auto* self = const_cast<TableModel*>(this);  // the writer only reads
        self->fields(w, self->p_, self->in_, self->out_, self->core_);
        return d;
    }

    Result load(const std::vector<double>& d) override {
        // Read into fresh values: a state that does not fit changes nothing.
        Params p{};
        In in{};
        Out out{};
        std::unique_ptr<Core> core;
        StateReader r(d);
        if (!fields(r, p, in, out, core) || !r.finished()) return Result::error(r.problem());
        p_ = p;
        in_ = in;
        out_ = out;
        core_ = std::move(core);
        return Result::ok();
    }

protected:
    // After the core is made: prepare the outputs before the first step.
    virtual Result start() = 0;
    // One communication step of the core; the outputs are read from it after.
    virtual Result step(double t, double h) = 0;

    Params p_;
    In in_;
    Out out_;
    std::unique_ptr<Core> core_;

private:
    std::optional<std::string> parameter_problem(const Params& p) const { return check_(p); }
    static Core make_core(const Params& p, double start_time) {
        if constexpr (std::is_constructible_v<Core, const Params&, double>) return Core(p, start_time);
        else return Core(p);  // a core that keeps no clock of its own
    }

    Result with_outputs(Result r) {
        if (r.status != Status::Error) out_ = core_->outputs();
        return r;
    }

    const Signal<In, Out>* input(unsigned vr) const {
        const unsigned k = vr - kFirstInputReference;
        return vr >= kFirstInputReference && k < inputs_.size() ? inputs_[k] : nullptr;
    }
    const Signal<In, Out>* output(unsigned vr) const {
        const unsigned k = vr - kFirstOutputReference;
        return vr >= kFirstOutputReference && k < outputs_.size() ? outputs_[k] : nullptr;
    }

    // The whole state: parameters, inputs, outputs, then the core's fields
    // when there is a core. Reading checks the parameters like fmi2SetReal does.
    template <class Archive>
    bool fields(Archive& a, Params& p, In& in, Out& out, std::unique_ptr<Core>& core) const {
        if (!parameter_fields(a, p)) return false;
        bool has_core = core != nullptr;
        if (!input_fields(a, *signals_, in) || !output_fields(a, *signals_, out) || !a("initialized", has_core))
            return false;
        if (!has_core) return true;
        if (!core) {
            if (auto problem = parameter_problem(p)) return a.refuse(*problem);
            core = std::make_unique<Core>(make_core(p, 0.0));
        }
        return core->fields(a);
    }

    Check check_;
    const SignalTable<In, Out>* signals_;
    std::vector<const Signal<In, Out>*> inputs_, outputs_;
};

// Who an FMU is: see each *_signals.def (HDJ_*_FMU).
struct Identity {
    const char* identifier;
    double state_magic;    // marks its serialised states: each hdjoint FMU its own
    double state_version;  // raised whenever the saved fields change
    const char* description;
};

// The ModelInfo of the FMU whose Model is M (a TableModel): the parameters
// `keep` accepts, then the signals of M's table. Built once.
template <class M, class Keep>
const ModelInfo& describe_model(const Identity& who, Keep keep) {
    static const ModelInfo info = [&] {
        ModelInfo i;
        i.model_name = i.model_identifier = who.identifier;
        i.state_magic = who.state_magic;
        i.state_version = who.state_version;
        i.description = who.description;
        i.variables = parameter_variables<typename M::Params>(keep);
        const M model;
        for (Variable& v : model.signal_variables()) i.variables.push_back(v);
        i.create = [] { return std::unique_ptr<Model>(new M()); };
        return i;
    }();
    return info;
}

}  // namespace hdjoint::fmu
