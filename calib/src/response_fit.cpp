#include "response_fit.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <system_error>

namespace fpp::calib {

namespace fs = std::filesystem;

namespace {

// The simulated rig's projector gamma recorded in a ramp's metadata, if any.
std::optional<double> simulated_gamma(const ResponseRamp& ramp) {
    if (ramp.metadata_yaml.empty())
        return std::nullopt;
    try {
        const YAML::Node metadata = YAML::Load(ramp.metadata_yaml);
        const YAML::Node gamma = metadata["projector_gamma"];
        if (!gamma.IsDefined() || !gamma.IsScalar())
            return std::nullopt;
        const double value = gamma.as<double>();
        return std::isfinite(value) && value > 0 ? std::optional<double>(value) : std::nullopt;
    } catch (const YAML::Exception&) {
        return std::nullopt; // free-form metadata: not ours to judge
    }
}

// printf-style formatting of numbers for the report.
template <class... Values> std::string format(const char* pattern, Values... values) {
    char text[160];
    std::snprintf(text, sizeof text, pattern, values...);
    return text;
}

} // namespace

std::optional<fs::path> find_response_ramp(const fs::path& path) {
    std::error_code ec;
    if (fs::is_regular_file(path / "ramp.yaml", ec))
        return path;
    if (fs::is_regular_file(path / kSessionResponseFolder / "ramp.yaml", ec))
        return path / kSessionResponseFolder;
    return std::nullopt;
}

ProjectorResponse fit_and_report_response(const fs::path& ramp_folder, std::ostream& out) {
    const ResponseRamp ramp = read_response_ramp(ramp_folder);
    const ProjectorResponse response = fit_projector_response(ramp);
    const std::optional<double> gamma = simulated_gamma(ramp);
    const std::size_t pixels = ramp.frames.front().size().area();
    out << "projector response from " << ramp_folder.string() << ": " << response.pixels_used
        << " of " << pixels << " camera pixels used (lit, never saturated)\n";
    out << (gamma ? format("  level  emitted  rig's (l/255)^%g    error\n", *gamma)
                  : std::string("  level  emitted\n"));
    double worst = 0;
    for (std::size_t k = 0; k < response.levels.size(); ++k) {
        out << format("  %5.0f  %7.4f", response.levels[k], response.emitted[k]);
        if (gamma) {
            const double truth = std::pow(response.levels[k] / 255.0, *gamma);
            const double error = response.emitted[k] - truth;
            worst = std::max(worst, std::abs(error));
            out << format("  %16.4f  %+.5f", truth, error);
        }
        out << "\n";
    }
    if (gamma)
        out << format("worst error against the simulated rig's response: %.5f (relative light)\n",
                      worst);
    return response;
}

} // namespace fpp::calib
