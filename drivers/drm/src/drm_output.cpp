#include <fpp/drivers/drm_output.hpp>

#include <fpp/drivers/device_error.hpp>
#include <fpp/error.hpp>

#include <cmath>
#include <cstdio>
#include <optional>

namespace fpp::drivers {
namespace {

std::string describe(const DrmModeInfo& mode) {
    char text[64];
    std::snprintf(text, sizeof text, "%dx%d@%.2f%s", mode.width, mode.height, mode.refresh_hz,
                  mode.preferred ? "*" : "");
    return text;
}

std::optional<int> parse_positive(const std::string& text) {
    if (text.empty() || text.size() > 5)
        return std::nullopt;
    int value = 0;
    for (const char c : text) {
        if (c < '0' || c > '9')
            return std::nullopt;
        value = value * 10 + (c - '0');
    }
    if (value <= 0)
        return std::nullopt;
    return value;
}

} // namespace

DrmModeSpec parse_drm_mode(const std::string& text) {
    const auto bad = [&] {
        return InputError("display settings", "mode",
                          "'" + text + "' is not WIDTHxHEIGHT or WIDTHxHEIGHT@HZ");
    };
    const std::size_t x = text.find('x');
    if (x == std::string::npos)
        throw bad();
    const std::size_t at = text.find('@', x);
    const auto width = parse_positive(text.substr(0, x));
    const auto height = parse_positive(
        text.substr(x + 1, at == std::string::npos ? std::string::npos : at - x - 1));
    if (!width || !height)
        throw bad();
    DrmModeSpec spec{*width, *height, 0.0};
    if (at != std::string::npos) {
        const std::string rate = text.substr(at + 1);
        char* end = nullptr;
        spec.refresh_hz = std::strtod(rate.c_str(), &end);
        if (rate.empty() || end != rate.c_str() + rate.size() || !(spec.refresh_hz > 0.0) ||
            spec.refresh_hz > 1000.0)
            throw bad();
    }
    return spec;
}

DrmOutputChoice choose_drm_output(const std::vector<DrmConnectorInfo>& connectors,
                                  const DrmOutputRequest& request, const std::string& device) {
    std::string present;
    for (const auto& c : connectors)
        present += (present.empty() ? "" : ", ") + c.name + (c.connected ? "" : " (disconnected)");
    if (present.empty())
        present = "none";

    std::optional<std::size_t> chosen;
    for (std::size_t i = 0; i < connectors.size() && !chosen; ++i) {
        const bool named = request.connector.empty() || connectors[i].name == request.connector;
        if (named && connectors[i].connected && !connectors[i].modes.empty())
            chosen = i;
    }
    if (!chosen) {
        if (request.connector.empty())
            throw DeviceError(DeviceKind::display, device,
                              "no connected connector with modes (connectors: " + present + ")");
        throw DeviceError(DeviceKind::display, device,
                          "connector " + request.connector +
                              " is not present and connected (connectors: " + present + ")");
    }
    const auto& modes = connectors[*chosen].modes;

    if (request.mode.empty()) {
        for (std::size_t m = 0; m < modes.size(); ++m)
            if (modes[m].preferred)
                return {*chosen, m};
        return {*chosen, 0};
    }
    const DrmModeSpec spec = parse_drm_mode(request.mode);
    std::optional<std::size_t> best;
    const auto better = [&](std::size_t a, std::size_t b) { // is a better than b?
        if (spec.refresh_hz > 0.0) {
            const double da = std::abs(modes[a].refresh_hz - spec.refresh_hz);
            const double db = std::abs(modes[b].refresh_hz - spec.refresh_hz);
            if (da != db)
                return da < db;
        }
        if (modes[a].preferred != modes[b].preferred)
            return modes[a].preferred;
        return modes[a].refresh_hz > modes[b].refresh_hz;
    };
    for (std::size_t m = 0; m < modes.size(); ++m) {
        if (modes[m].width != spec.width || modes[m].height != spec.height)
            continue;
        if (spec.refresh_hz > 0.0 && std::abs(modes[m].refresh_hz - spec.refresh_hz) > 0.5)
            continue;
        if (!best || better(m, *best))
            best = m;
    }
    if (!best) {
        std::string listed;
        for (const auto& m : modes)
            listed += (listed.empty() ? "" : ", ") + describe(m);
        throw DeviceError(DeviceKind::display, device,
                          "connector " + connectors[*chosen].name + " has no mode " + request.mode +
                              " (modes: " + listed + ")");
    }
    return {*chosen, *best};
}

} // namespace fpp::drivers
