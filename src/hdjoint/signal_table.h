#pragma once
// The inputs and outputs of a sampled or simulated model, declared once in a
// list macro (estimator_signals.def, plant_signals.def,
// controller_signals.def):
//
//   #define HDJ_..._SIGNALS(INPUT, OUTPUT, SIGNAL)
//     INPUT(name, unit, description)              an FMU input
//     OUTPUT(name, unit, initial, description)    an FMU output; `initial` lists the
//         inputs (space-separated, "" for none) its value at initialisation depends on
//     SIGNAL(name, unit, description)             an output of the batch path only
//
// From the list come the Inputs/Outputs structs (HDJ_MEMBER), the table of
// Signal rows (HDJ_*_ROW) that the FMU (get/set, value references, XML,
// documentation, state) and the Python bindings read.
#include <vector>

namespace hdjoint {

enum class SignalKind { Input, Output, Internal };

template <class In, class Out>
struct Signal {
    const char* name;
    const char* unit;
    const char* description;
    SignalKind kind;
    const char* initial_dependencies;  // outputs: the inputs their initial value depends on
    double In::*input;                 // inputs
    double Out::*output;               // outputs and internal signals
};

template <class In, class Out>
using SignalTable = std::vector<Signal<In, Out>>;

// The inputs, or the outputs and internal signals, as named state fields.
template <class Archive, class In, class Out>
bool input_fields(Archive& a, const SignalTable<In, Out>& table, In& in) {
    for (const Signal<In, Out>& s : table)
        if (s.kind == SignalKind::Input && !a(s.name, in.*(s.input))) return false;
    return true;
}
template <class Archive, class In, class Out>
bool output_fields(Archive& a, const SignalTable<In, Out>& table, Out& out) {
    for (const Signal<In, Out>& s : table)
        if (s.kind != SignalKind::Input && !a(s.name, out.*(s.output))) return false;
    return true;
}

}  // namespace hdjoint

// A struct member per row; HDJ_SKIP leaves a row out.
#define HDJ_MEMBER(name, ...) double name = 0.0;
#define HDJ_SKIP(...)
// Table rows; `In` and `Out` are the Inputs and Outputs types in scope.
#define HDJ_INPUT_ROW(name, unit, description) \
    {#name, unit, description, ::hdjoint::SignalKind::Input, "", &In::name, nullptr},
#define HDJ_OUTPUT_ROW(name, unit, initial, description) \
    {#name, unit, description, ::hdjoint::SignalKind::Output, initial, nullptr, &Out::name},
#define HDJ_SIGNAL_ROW(name, unit, description) \
    {#name, unit, description, ::hdjoint::SignalKind::Internal, "", nullptr, &Out::name},
// Defines `const SignalTable<In, Out>& function()` holding the rows of LIST.
#define HDJ_DEFINE_SIGNAL_TABLE(function, InType, OutType, LIST)                                \
    const ::hdjoint::SignalTable<InType, OutType>& function() {                                 \
        using In = InType;                                                                      \
        using Out = OutType;                                                                    \
        static const ::hdjoint::SignalTable<In, Out> table = {LIST(HDJ_INPUT_ROW, HDJ_OUTPUT_ROW, HDJ_SIGNAL_ROW)}; \
        return table;                                                                           \
    }
