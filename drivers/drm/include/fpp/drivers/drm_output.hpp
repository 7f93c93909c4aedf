#pragma once
// Choosing the display output (connector and mode) from what the DRM card
// reports, apart from the ioctls so that the choice can be tested without a
// device.
#include <cstddef>
#include <string>
#include <vector>

namespace fpp::drivers {

struct DrmModeInfo {
    int width = 0; // active pixels
    int height = 0;
    double refresh_hz = 0.0;
    bool preferred = false; // the sink's preferred mode (EDID)
};

struct DrmConnectorInfo {
    std::string name; // "HDMI-A-1", "DSI-1": type name, '-', type index
    bool connected = false;
    std::vector<DrmModeInfo> modes; // in the order the card lists them
};

// What the board config asks for. Empty connector: the first connected one.
// Mode: "" (the preferred mode, else the first), "WxH" (the first such mode,
// preferring the preferred one, then the highest refresh) or "WxH@R" (the
// refresh nearest R, within 0.5 Hz).
struct DrmOutputRequest {
    std::string connector;
    std::string mode;
};

struct DrmOutputChoice {
    std::size_t connector = 0; // index into the connector list
    std::size_t mode = 0;      // index into that connector's modes
};

struct DrmModeSpec {
    int width = 0;
    int height = 0;
    double refresh_hz = 0.0; // 0 = any
};

// Parses "WxH" or "WxH@R". Throws fpp::InputError("display settings", "mode",
// ...) for anything else.
DrmModeSpec parse_drm_mode(const std::string& text);

// Throws DeviceError(device, ...) when nothing fits: no connected connector,
// the named one absent or disconnected (the message lists those present), or
// no mode of the requested size (the message lists the modes).
DrmOutputChoice choose_drm_output(const std::vector<DrmConnectorInfo>& connectors,
                                  const DrmOutputRequest& request,
                                  const std::string& device = "display");

} // namespace fpp::drivers
