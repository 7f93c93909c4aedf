#include "fpp/scanner/settings_file.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/yaml_fields.hpp"

#include <string>

namespace fpp::scanner {

namespace {
constexpr const char* kFormat = "fpp-scanner-settings/1";
}

std::optional<ScannerSettings> read_settings_file(const std::filesystem::path& path) {
    if (!std::filesystem::exists(path))
        return std::nullopt;
    const yaml_fields::Reader r(path);
    const YAML::Node root = r.load_file();
    r.expect_map(root, "", {"format", "exposure_us"});
    if (r.string_value(r.require(root, "", "format"), "format") != kFormat)
        r.fail(root["format"], "format", std::string("must be ") + kFormat);
    ScannerSettings s;
    s.exposure_us = r.real_value(r.require(root, "", "exposure_us"), "exposure_us");
    if (!(s.exposure_us >= kMinExposureUs && s.exposure_us <= kMaxExposureUs))
        r.fail(root["exposure_us"], "exposure_us", "must be in 10..1000000");
    return s;
}

void write_settings_file(const std::filesystem::path& path, const ScannerSettings& settings) {
    write_file_atomically(path, std::string("format: ") + kFormat + "\nexposure_us: " +
                                    yaml_fields::format_real(settings.exposure_us) + "\n");
}

} // namespace fpp::scanner
