#pragma once
// The projector through DRM/KMS (libdrm). One dumb buffer (XRGB8888, grey
// pattern in every channel) per pattern, rendered once in prepare().
//
// Atomic KMS when the card offers it: the first show() tests the full
// modeset (connector CRTC_ID, CRTC MODE_ID and ACTIVE, primary plane) with
// TEST_ONLY, then commits it once with ALLOW_MODESET; every later show()
// commits only the plane's FB_ID with NONBLOCK | PAGE_FLIP_EVENT. Without
// atomic: drmModeSetCrtc once, then drmModePageFlip with PAGE_FLIP_EVENT.
// Flip events are read from the card with poll + drmHandleEvent; at most one
// flip is pending; every completed flip is logged with its vblank sequence and
// CLOCK_MONOTONIC timestamp. restore() (and the destructor) puts back the CRTC
// configuration found at open.
#include <chrono>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <fpp/drivers/display.hpp>
#include <fpp/drivers/drm_output.hpp>

namespace fpp::drivers {

struct DrmDisplaySettings {
    std::string card =
        "auto";              // "/dev/dri/card0", or "auto": the first card with an output that fits
    DrmOutputRequest output; // connector and mode
    bool allow_atomic = true; // false forces the legacy path
};

class DrmDisplay final : public Display {
public:
    // Opens the card, picks connector, mode and CRTC; shows nothing yet.
    // Throws DeviceError naming the card ("display /dev/dri/card0") if it
    // cannot be opened or offers no fitting output.
    explicit DrmDisplay(const DrmDisplaySettings& settings);
    ~DrmDisplay() override;

    Size size() const override;
    void prepare(const std::vector<Image<std::uint8_t>>& patterns) override;
    void show(std::size_t index) override;
    FlipEvent wait_flip(std::chrono::milliseconds timeout) override;
    void restore() override;

    bool atomic() const;
    const std::string& name() const; // "display <card path>"
    // Every completed flip since open, oldest first.
    const std::vector<FlipEvent>& flip_log() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace fpp::drivers
