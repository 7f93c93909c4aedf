#include "sim_gige_camera.hpp"

#include "fpp/drivers/device_error.hpp"
#include "fpp/error.hpp"
#include "fpp/scanner/reconnecting_camera.hpp"

#include <algorithm>
#include <cstdio>
#include <optional>

#if FPP_HAVE_ARAVIS
#include <fpp/drivers/aravis_camera.hpp>
#include <fpp/drivers/aravis_fake_camera.hpp>
#endif

namespace fpp::scanner {

#if FPP_HAVE_ARAVIS
namespace {

std::unique_ptr<drivers::Camera> open_driver(const std::string& address,
                                             const drivers::CameraSettings& settings) {
    return std::make_unique<drivers::AravisCamera>(address, settings);
}

class GigeLinkCamera final : public SimGigeCamera {
public:
    GigeLinkCamera(sim::SimCamera& sensor, const std::string& address,
                   const drivers::CameraSettings& settings, const Logger& log)
        : sensor_(sensor), address_(address), fake_(std::in_place, sensor.size(), address),
          driver_([address, settings] { return open_driver(address, settings); },
                  open_driver(address, settings), "camera " + address, log),
          timeout_(settings.frame_timeout) {}

    void unplug() override { fake_.reset(); }
    void plug() override {
        if (!fake_)
            fake_.emplace(sensor_.size(), address_);
    }

    Size size() const override { return driver_.size(); }
    int bit_depth() const override { return driver_.bit_depth(); }
    void start() override {
        sensor_.start();
        driver_.start();
    }
    void stop() override {
        driver_.stop();
        sensor_.stop();
    }
    // Both ends must accept an exposure: the simulated sensor and the
    // GigE camera that carries its frames.
    drivers::ExposureRange exposure_range_us() const override {
        const drivers::ExposureRange sensor = sensor_.exposure_range_us();
        const drivers::ExposureRange link = driver_.exposure_range_us();
        return {std::max(sensor.min_us, link.min_us), std::min(sensor.max_us, link.max_us)};
    }
    void set_exposure_us(double exposure_us) override {
        // Checked against both before either changes.
        const drivers::ExposureRange range = exposure_range_us();
        if (!range.contains(exposure_us)) {
            char text[160];
            std::snprintf(text, sizeof text,
                          "%.10g us is outside the camera's exposure range %.10g..%.10g us",
                          exposure_us, range.min_us, range.max_us);
            throw InputError("camera settings", "exposure_us", text);
        }
        sensor_.set_exposure_us(exposure_us);
        driver_.set_exposure_us(exposure_us);
    }
    void software_trigger() override {
        // The image must be in the fake camera before its trigger arrives:
        // it fills the frame when it sees the trigger.
        sensor_.software_trigger();
        const Frame image = sensor_.next_frame(timeout_).frame;
        if (fake_)
            fake_->set_image(image);
        driver_.software_trigger();
    }
    drivers::CapturedFrame next_frame(std::chrono::milliseconds timeout) override {
        return driver_.next_frame(timeout);
    }
    std::size_t frames_waiting() const override { return driver_.frames_waiting(); }

private:
    sim::SimCamera& sensor_;
    std::string address_;
    std::optional<drivers::AravisFakeCamera> fake_; // before the driver that connects to it
    ReconnectingCamera driver_;
    std::chrono::milliseconds timeout_;
};

} // namespace

std::unique_ptr<SimGigeCamera> make_sim_gige_camera(sim::SimCamera& sensor,
                                                    const std::string& address,
                                                    const drivers::CameraSettings& settings,
                                                    const Logger& log) {
    return std::make_unique<GigeLinkCamera>(sensor, address, settings, log);
}
#else
std::unique_ptr<SimGigeCamera> make_sim_gige_camera(sim::SimCamera&, const std::string& address,
                                                    const drivers::CameraSettings&, const Logger&) {
    throw drivers::DeviceError(drivers::DeviceKind::camera, "camera " + address,
                               "Aravis support is not built into this binary (aravis-0.8 was "
                               "not found at build time)");
}
#endif

} // namespace fpp::scanner
