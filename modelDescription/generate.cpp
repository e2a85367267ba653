// Writes an FMU's modelDescription.xml, documentation/index.html and
// sources/buildDescription.xml from its variable table (this_model()), so
// the XML can never drift from the model. Linked once per FMU.
//   generate OUT_DIR FMI_VERSION SOURCE...   (2 or 3; sources relative to the FMU's sources/)
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "description.h"

namespace {
bool write(const std::string& path, const std::string& text) {
    std::ofstream f(path, std::ios::binary);
    f << text;
    return static_cast<bool>(f);
}
}  // namespace

int main(int argc, char** argv) {
    const std::string version = argc >= 3 ? argv[2] : "";
    if (version != "2" && version != "3") {
        std::cerr << "usage: " << argv[0] << " OUT_DIR 2|3 [SOURCE...]\n";
        return 2;
    }
    const int fmi = version == "3" ? 3 : 2;
    const std::string out = argv[1];
    const std::vector<std::string> sources(argv + 3, argv + argc);
    try {
        const auto& info = hdjoint::fmu::this_model();
        if (!write(out + "/modelDescription.xml", hdjoint::fmu::model_description_xml(info, sources, fmi)) ||
            !write(out + "/documentation/index.html", hdjoint::fmu::documentation_html(info, fmi)) ||
            !write(out + "/sources/buildDescription.xml", hdjoint::fmu::build_description_xml(info, sources, fmi))) {
            std::cerr << "cannot write into " << out << "\n";
            return 1;
        }
    } catch (const std::exception& e) {
        std::cerr << e.what() << "\n";
        return 1;
    }
    return 0;
}
