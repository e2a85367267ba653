#pragma once
// Texts generated from a ModelInfo: modelDescription.xml, the FMU's
// documentation page and sources/buildDescription.xml, plus the GUID the
// binary checks at instantiation (a hash of the variable table, so the XML
// and the binary can never disagree unnoticed).
#include <string>
#include <vector>

#include "model.h"

namespace hdjoint::fmu {

std::string guid(const ModelInfo& info);
// fmi_version: 2 or 3 (the FMU's two builds describe the same model).
std::string model_description_xml(const ModelInfo& info, const std::vector<std::string>& sources, int fmi_version);
std::string build_description_xml(const ModelInfo& info, const std::vector<std::string>& sources, int fmi_version);
std::string documentation_html(const ModelInfo& info, int fmi_version);

}  // namespace hdjoint::fmu
