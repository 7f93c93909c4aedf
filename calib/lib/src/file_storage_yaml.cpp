// YAML text checked by yaml-cpp before OpenCV's FileStorage parses it
// (calibration_reader.hpp).

#include "calibration_reader.hpp"

#include <yaml-cpp/yaml.h>

#include <string>

namespace fpp::calib::detail {

void refuse_malformed_yaml(std::string_view text, const fs::path& origin) {
    std::string yaml(text);
    // OpenCV's "%YAML:1.0" is not YAML's directive syntax: blanked, so that
    // yaml-cpp's line numbers stay the file's.
    if (yaml.starts_with("%YAML"))
        yaml.erase(0, std::min(yaml.find('\n'), yaml.size()));
    try {
        (void)YAML::LoadAll(yaml);
    } catch (const YAML::Exception& e) {
        const std::string where =
            e.mark.is_null() ? std::string() : "line " + std::to_string(e.mark.line + 1);
        throw InputError(origin, where, "not valid YAML: " + e.msg);
    }
}

} // namespace fpp::calib::detail
