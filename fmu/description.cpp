#include "description.h"

#include "hdjoint/joint_plant.h"
#include "hdjoint/sample_clock.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace hdjoint::fmu {

namespace {

const char* causality_name(Causality c) {
    switch (c) {
        case Causality::Parameter: return "parameter";
        case Causality::Input: return "input";
        case Causality::Output: return "output";
        case Causality::Local: return "local";
    }
    return "local";
}

std::string escape(const std::string& s) {
    std::string out;
    for (char ch : s) {
        switch (ch) {
            case '&': out += "&amp;"; break;
            case '<': out += "&lt;"; break;
            case '>': out += "&gt;"; break;
            case '"': out += "&quot;"; break;
            default: out += ch;
        }
    }
    return out;
}

std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

// SI base-unit exponents of every unit the models use (kg, m, s, A, rad).
struct BaseUnits { int kg, m, s, A, rad; };
const std::map<std::string, BaseUnits>& unit_table() {
    static const std::map<std::string, BaseUnits> table = {
        {"A/rad", {0, 0, 0, 1, -1}}, {"A.s/rad", {0, 0, 1, 1, -1}},  // JointController gains
        {"1", {0, 0, 0, 0, 0}},       {"rad", {0, 0, 0, 0, 1}},      {"rad/s", {0, 0, -1, 0, 1}},
        {"A", {0, 0, 0, 1, 0}},       {"s", {0, 0, 1, 0, 0}},        {"N.m", {1, 2, -2, 0, 0}},
        {"N.m/A", {1, 2, -2, -1, 0}}, {"N.m/rad", {1, 2, -2, 0, -1}}, {"kg.m2", {1, 2, 0, 0, 0}},
        {"N.m.s/rad", {1, 2, -1, 0, -1}}, {"1/(N.m)", {-1, -2, 2, 0, 0}}, {"1/rad", {0, 0, 0, 0, -1}},
        {"1/s", {0, 0, -1, 0, 0}},
        {"N.m/s", {1, 2, -3, 0, 0}},      {"rad/s2", {0, 0, -2, 0, 1}},
    };
    return table;
}

std::string unit_definitions(const ModelInfo& info) {
    std::set<std::string> used;
    for (const Variable& v : info.variables) used.insert(v.unit);
    std::ostringstream x;
    x << "  <UnitDefinitions>\n";
    for (const std::string& u : used) {
        auto it = unit_table().find(u);
        if (it == unit_table().end()) throw std::runtime_error("unit '" + u + "' has no base-unit definition");
        const BaseUnits& b = it->second;
        x << "    <Unit name=\"" << escape(u) << "\"><BaseUnit";
        if (b.kg) x << " kg=\"" << b.kg << "\"";
        if (b.m) x << " m=\"" << b.m << "\"";
        if (b.s) x << " s=\"" << b.s << "\"";
        if (b.A) x << " A=\"" << b.A << "\"";
        if (b.rad) x << " rad=\"" << b.rad << "\"";
        x << "/></Unit>\n";
    }
    x << "  </UnitDefinitions>\n";
    return x.str();
}

// 64-bit FNV-1a, run twice with different seeds for 128 bits.
std::uint64_t fnv1a(const std::string& s, std::uint64_t seed) {
    std::uint64_t h = seed;
    for (unsigned char c : s) {
        h ^= c;
        h *= 1099511628211ull;
    }
    return h;
}

// The variables named in `names` (space-separated), each as `reference(index)`
// gives it (index: 0-based in info.variables); every one must have causality `of`.
template <class Reference>
std::string references(const ModelInfo& info, const Variable& dependent, const std::string& names, Causality of,
                       Reference reference) {
    std::istringstream in(names);
    std::string name, list;
    while (in >> name) {
        std::size_t index = info.variables.size();
        for (std::size_t i = 0; i < info.variables.size() && index == info.variables.size(); ++i)
            if (info.variables[i].name == name && info.variables[i].causality == of) index = i;
        if (index == info.variables.size())
            throw std::runtime_error(dependent.name + " depends on '" + name + "', not a variable of that kind");
        list += (list.empty() ? "" : " ") + reference(index);
    }
    return list;
}

// A variable's initial value: the inputs it depends on (FMI 2.0: 1-based indices).
std::string initial_dependencies(const ModelInfo& info, const Variable& v) {
    return references(info, v, v.initial_dependencies, Causality::Input,
                      [](std::size_t i) { return std::to_string(i + 1); });
}

}  // namespace

std::string guid(const ModelInfo& info) {
    std::ostringstream canonical;
    canonical << info.model_identifier << '|';
    for (const Variable& v : info.variables)
        canonical << v.name << ',' << v.value_reference << ',' << causality_name(v.causality) << ',' << v.unit
                  << ',' << number(v.start) << ',' << number(v.min) << ',' << number(v.max) << ';';
    const std::uint64_t a = fnv1a(canonical.str(), 14695981039346656037ull);
    const std::uint64_t b = fnv1a(canonical.str(), 0x9e3779b97f4a7c15ull);
    char buf[48];
    std::snprintf(buf, sizeof buf, "{%08x-%04x-%04x-%04x-%012llx}", static_cast<unsigned>(a >> 32),
                  static_cast<unsigned>((a >> 16) & 0xffff), static_cast<unsigned>(a & 0xffff),
                  static_cast<unsigned>(b >> 48), static_cast<unsigned long long>(b & 0xffffffffffffull));
    return buf;
}

namespace {

// The elements both versions write alike.
std::string common_elements(const ModelInfo& info) {
    std::ostringstream x;
    x << unit_definitions(info);
    x << "  <LogCategories>\n"
      << "    <Category name=\"logStatusWarning\" description=\"recoverable problems\"/>\n"
      << "    <Category name=\"logStatusError\" description=\"errors: bad input, illegal calls\"/>\n"
      << "    <Category name=\"logAll\" description=\"everything\"/>\n  </LogCategories>\n";
    x << "  <DefaultExperiment startTime=\"0\" stopTime=\"10\" stepSize=\"0.001\"/>\n";
    return x.str();
}

std::string source_files(const std::vector<std::string>& sources, const char* element, const char* indent) {
    std::string x;
    for (const std::string& s : sources)
        if (s.size() > 4 && s.substr(s.size() - 4) == ".cpp")
            x += std::string(indent) + "<" + element + " name=\"" + escape(s) + "\"/>\n";
    return x;
}

std::string bounds(const Variable& v) {
    std::string x;
    if (v.min > -1e299) x += " min=\"" + number(v.min) + "\"";
    if (v.max < 1e299) x += " max=\"" + number(v.max) + "\"";
    return x;
}

// An output's dependencies in the running model: none on the inputs (they act
// inside doStep only), and in Model Exchange the states it is computed from.
template <class Reference>
std::string run_dependencies(const ModelInfo& info, const Variable& output, Reference reference) {
    if (!info.model_exchange()) return "";
    return references(info, output, output.state_dependencies, Causality::Local, reference);
}

bool is_state(const Variable& v) {
    return v.causality == Causality::Local && v.value_reference >= kFirstStateReference &&
           v.value_reference < kFirstDerivativeReference;
}
bool is_derivative(const Variable& v) { return v.derivative_of >= 0; }
bool is_event_indicator(const Variable& v) {
    return v.causality == Causality::Local && !is_state(v) && !is_derivative(v);
}

std::string fmi2_description(const ModelInfo& info, const std::vector<std::string>& sources) {
    std::ostringstream x;
    x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<!-- Generated from the hdjoint parameter and variable tables; do not edit. -->\n"
      << "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"" << info.model_name << "\" guid=\""
      << guid(info) << "\"\n  description=\"" << escape(info.description)
      << "\"\n  generationTool=\"hdjoint\" version=\"0.1.0\" variableNamingConvention=\"flat\""
      << " numberOfEventIndicators=\"" << info.event_indicators << "\">\n";
    if (info.model_exchange())
        x << "  <ModelExchange modelIdentifier=\"" << info.model_identifier
          << "\" canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\">\n    <SourceFiles>\n"
          << source_files(sources, "File", "      ") << "    </SourceFiles>\n  </ModelExchange>\n";
    x << "  <CoSimulation modelIdentifier=\"" << info.model_identifier
      << "\" canHandleVariableCommunicationStepSize=\"true\" canInterpolateInputs=\"false\""
      << " canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\">\n    <SourceFiles>\n"
      << source_files(sources, "File", "      ") << "    </SourceFiles>\n  </CoSimulation>\n";
    x << common_elements(info);
    x << "  <ModelVariables>\n";
    std::vector<std::size_t> outputs, derivatives, states;
    std::map<unsigned, std::size_t> index_of;  // value reference -> 1-based index
    for (std::size_t i = 0; i < info.variables.size(); ++i) index_of[info.variables[i].value_reference] = i + 1;
    for (std::size_t i = 0; i < info.variables.size(); ++i) {
        const Variable& v = info.variables[i];
        x << "    <!-- " << i + 1 << " -->\n    <ScalarVariable name=\"" << escape(v.name)
          << "\" valueReference=\"" << v.value_reference << "\" causality=\"" << causality_name(v.causality)
          << "\"";
        switch (v.causality) {
            case Causality::Parameter: x << " variability=\"fixed\" initial=\"exact\""; break;
            case Causality::Input: x << " variability=\"continuous\""; break;
            case Causality::Output:
                x << " variability=\"continuous\" initial=\"calculated\"";
                outputs.push_back(i + 1);
                break;
            case Causality::Local:
                x << " variability=\"continuous\" initial=\"calculated\"";
                if (is_state(v)) states.push_back(i + 1);
                if (is_derivative(v)) derivatives.push_back(i + 1);
                break;
        }
        x << "\n      description=\"" << escape(v.description) << "\">\n      <Real unit=\"" << escape(v.unit)
          << "\"";
        if (v.causality == Causality::Parameter || v.causality == Causality::Input)
            x << " start=\"" << number(v.start) << "\"";
        if (is_derivative(v)) x << " derivative=\"" << index_of.at(static_cast<unsigned>(v.derivative_of)) << "\"";
        x << bounds(v) << "/>\n    </ScalarVariable>\n";
    }
    auto index = [](std::size_t i) { return std::to_string(i + 1); };
    x << "  </ModelVariables>\n  <ModelStructure>\n    <Outputs>\n";
    // Outputs change only inside doStep: no direct feedthrough from inputs,
    // so masters see no algebraic loop when a controller closes the loop.
    for (std::size_t k : outputs)
        x << "      <Unknown index=\"" << k << "\" dependencies=\""
          << run_dependencies(info, info.variables[k - 1], index) << "\"/>\n";
    x << "    </Outputs>\n";
    if (!derivatives.empty()) {
        x << "    <Derivatives>\n";
        for (std::size_t k : derivatives) x << "      <Unknown index=\"" << k << "\"/>\n";
        x << "    </Derivatives>\n";
    }
    x << "    <InitialUnknowns>\n";
    // At initialisation an output may depend on start inputs: the table says
    // which (dependencies="" for none, so masters see no initialisation loop).
    // The states and derivatives (Model Exchange) are computed there too.
    std::vector<std::size_t> initial = outputs;
    initial.insert(initial.end(), states.begin(), states.end());
    initial.insert(initial.end(), derivatives.begin(), derivatives.end());
    std::sort(initial.begin(), initial.end());
    for (std::size_t k : initial) {
        const Variable& v = info.variables[k - 1];
        x << "      <Unknown index=\"" << k << "\" dependencies=\"" << initial_dependencies(info, v) << "\"/>\n";
    }
    x << "    </InitialUnknowns>\n  </ModelStructure>\n</fmiModelDescription>\n";
    return x.str();
}

std::string fmi3_description(const ModelInfo& info) {
    std::ostringstream x;
    x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<!-- Generated from the hdjoint parameter and variable tables; do not edit. -->\n"
      << "<fmiModelDescription fmiVersion=\"3.0\" modelName=\"" << info.model_name << "\" instantiationToken=\""
      << guid(info) << "\"\n  description=\"" << escape(info.description)
      << "\"\n  generationTool=\"hdjoint\" version=\"0.1.0\" variableNamingConvention=\"flat\">\n";
    if (info.model_exchange())
        x << "  <ModelExchange modelIdentifier=\"" << info.model_identifier
          << "\" canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\"/>\n";
    x << "  <CoSimulation modelIdentifier=\"" << info.model_identifier
      << "\" canHandleVariableCommunicationStepSize=\"true\" canGetAndSetFMUState=\"true\""
      << " canSerializeFMUState=\"true\" hasEventMode=\"false\" canReturnEarlyAfterIntermediateUpdate=\"false\""
      << " providesIntermediateUpdate=\"false\"/>\n";
    x << common_elements(info);
    x << "  <ModelVariables>\n";
    x << "    <Float64 name=\"time\" valueReference=\"" << kTimeReference
      << "\" causality=\"independent\" variability=\"continuous\" unit=\"s\" description=\"simulation time\"/>\n";
    for (const Variable& v : info.variables) {
        x << "    <Float64 name=\"" << escape(v.name) << "\" valueReference=\"" << v.value_reference
          << "\" causality=\"" << causality_name(v.causality) << "\"";
        switch (v.causality) {
            case Causality::Parameter: x << " variability=\"fixed\" initial=\"exact\""; break;
            case Causality::Input: x << " variability=\"continuous\""; break;
            case Causality::Output:
            case Causality::Local: x << " variability=\"continuous\" initial=\"calculated\""; break;
        }
        x << " unit=\"" << escape(v.unit) << "\"";
        if (v.causality == Causality::Parameter || v.causality == Causality::Input)
            x << " start=\"" << number(v.start) << "\"";
        if (is_derivative(v)) x << " derivative=\"" << v.derivative_of << "\"";
        x << bounds(v) << "\n      description=\"" << escape(v.description) << "\"/>\n";
    }
    auto reference = [&](std::size_t i) { return std::to_string(info.variables[i].value_reference); };
    x << "  </ModelVariables>\n  <ModelStructure>\n";
    for (const Variable& v : info.variables)
        if (v.causality == Causality::Output)
            x << "    <Output valueReference=\"" << v.value_reference << "\" dependencies=\""
              << run_dependencies(info, v, reference) << "\"/>\n";
    for (const Variable& v : info.variables)
        if (is_derivative(v)) x << "    <ContinuousStateDerivative valueReference=\"" << v.value_reference << "\"/>\n";
    for (const Variable& v : info.variables) {
        if (v.causality != Causality::Output && !is_state(v) && !is_derivative(v)) continue;
        x << "    <InitialUnknown valueReference=\"" << v.value_reference << "\" dependencies=\""
          << references(info, v, v.initial_dependencies, Causality::Input, reference) << "\"/>\n";
    }
    for (const Variable& v : info.variables)
        if (is_event_indicator(v)) x << "    <EventIndicator valueReference=\"" << v.value_reference << "\"/>\n";
    x << "  </ModelStructure>\n</fmiModelDescription>\n";
    return x.str();
}

}  // namespace

std::string model_description_xml(const ModelInfo& info, const std::vector<std::string>& sources, int fmi_version) {
    return fmi_version == 3 ? fmi3_description(info) : fmi2_description(info, sources);
}

std::string build_description_xml(const ModelInfo& info, const std::vector<std::string>& sources, int fmi_version) {
    std::ostringstream x;
    x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<fmiBuildDescription fmiVersion=\"3.0\">\n"
      << "  <BuildConfiguration modelIdentifier=\"" << info.model_identifier
      << "\" description=\"Rebuild from sources/: C++17, include directory sources/ (holds Eigen and the"
      << " hdjoint headers); the FMI " << fmi_version << ".0 headers come from the importing tool.\">\n"
      << "    <SourceFileSet language=\"C++17\">\n";
    x << source_files(sources, "SourceFile", "      ");
    x << "    </SourceFileSet>\n  </BuildConfiguration>\n</fmiBuildDescription>\n";
    return x.str();
}

std::string documentation_html(const ModelInfo& info, int fmi_version) {
    const std::string error = fmi_version == 3 ? "fmi3Error" : "fmi2Error";
    const std::string warning = fmi_version == 3 ? "fmi3Warning" : "fmi2Warning";
    std::ostringstream h;
    h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" << info.model_name
      << "</title>\n<style>body{font-family:sans-serif;max-width:60em;margin:2em auto}"
      << "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:.2em .5em;text-align:left}"
      << "code{background:#f4f4f4}</style></head><body>\n<h1>" << info.model_name << "</h1>\n<p>"
      << escape(info.description) << "</p>\n"
      << "<p>FMI " << fmi_version << ".0 " << (info.model_exchange() ? "Model Exchange and " : "")
      << "Co-Simulation, built by <code>hdjoint</code>. Physics: Yu et al. 2018, eq. (1)-(31), with"
      << " the sign conventions <code>dtheta = theta_m/N - theta_l</code>, <code>dtheta_f = dtheta - wg(tau_w)"
      << " - theta_err</code>, <code>tau_f = tan(Cf*Kf*dtheta_f)/Cf</code>. The C++ sources are in"
      << " <code>sources/</code> (rebuild with <code>sources/buildDescription.xml</code>, include directory"
      << " <code>sources/</code>).</p>\n<h2>Variables</h2>\n<table><tr><th>name</th><th>causality</th>"
      << "<th>unit</th><th>start</th><th>range</th><th>description</th></tr>\n";
    for (const Variable& v : info.variables) {
        h << "<tr><td><code>" << escape(v.name) << "</code></td><td>" << causality_name(v.causality) << "</td><td>"
          << escape(v.unit) << "</td><td>" << (v.causality == Causality::Output ? "" : number(v.start))
          << "</td><td>";
        if (v.causality == Causality::Parameter) h << "[" << number(v.min) << ", " << number(v.max) << "]";
        h << "</td><td>" << escape(v.description) << "</td></tr>\n";
    }
    h << "</table>\n<h2>Errors</h2><p>Non-finite inputs, parameters outside their range, a torsion beyond the"
      << " atan law's asymptote and calls out of the FMI state machine return <code>" << error << "</code> with a"
      << " message through the logger naming the variable and value; recoverable filter problems return"
      << " <code>" << warning << "</code>.</p>\n<h2>Step size</h2><p>A <code>doStep</code> may run at most "
      << hdjoint::SampleClock::kMaxSamplesPerStep << " samples of a sampled model (estimator, controller) or "
      << number(hdjoint::JointPlant::kMaxSubstepsPerAdvance) << " integration substeps of the joint; a longer"
      << " step is refused whole with <code>" << error << "</code> (split it into shorter ones).</p>\n"
      << "<h2>Timing</h2><p>A sampled model (estimator, controller) runs the samples <code>start + k*Ts</code>"
      << " that fall in a step <code>[t, t+h)</code>, with the inputs set at <code>t</code>. The outputs read"
      << " after the step describe the last sample it ran: with <code>h = Ts</code>, those read at a"
      << " communication point <code>t</code> describe the sample at <code>t - Ts</code> (a master such as"
      << " fmpy records them at <code>t</code>: shift them by one sample to line them up with the inputs)."
      << " The joint integrates continuously: its outputs at <code>t</code> are its state at <code>t</code>.</p>\n"
      << "<h2>FMU state</h2><p>Serialised states carry this FMU's own magic number and state version; a state"
      << " of another FMU or version, a field that is not finite or outside its range, and a state-machine value"
      << " that the model cannot be in are refused with <code>" << error << "</code> naming the field.</p>\n"
      << "</body></html>\n";
    return h.str();
}

}  // namespace hdjoint::fmu
