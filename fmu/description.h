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
std::string model_description_xml(const ModelInfo& info, const std::vector<std::string>& sources);
std::string build_description_xml(const ModelInfo& info, const std::vector<std::string>& sources);
std::string documentation_html(const ModelInfo& info);

}  // namespace hdjoint::fmu
