#include "fpp/scanner/hardware_board.hpp"

#include "fpp/drivers/device_error.hpp"
#include "fpp/scanner/reconnecting_camera.hpp"

#include <stdexcept>
#include <string>
#include <utility>

#if FPP_HAVE_ARAVIS
#include <fpp/drivers/aravis_camera.hpp>
#endif
#if FPP_HAVE_DRM
#include <fpp/drivers/drm_display.hpp>
#endif
#if FPP_HAVE_GPIOD
#include <fpp/drivers/gpiod_lines.hpp>
#endif

namespace fpp::scanner {

namespace {

[[noreturn, maybe_unused]] void not_built(drivers::DeviceKind kind, const std::string& device,
                                          const char* library) {
    throw drivers::DeviceError(kind, device,
                               std::string("support is not built into this binary (") + library +
                                   " was not found at build time)");
}

#if FPP_HAVE_GPIOD
// `field`: the board file's key for the line, named in its errors.
drivers::GpioLineConfig line(const BoardConfig& board, const char* field, int offset,
                             bool active_low) {
    drivers::GpioLineConfig c;
    c.chip = board.gpio.chip;
    c.offset = static_cast<unsigned int>(offset);
    c.active_low = active_low;
    c.field = board.file.filename().string() + " gpio." + field;
    return c;
}
#endif

// The LED set to error while another device's error is on its way out: a
// failure of the LED itself must not replace that error.
void show_error(drivers::StatusLed& led) noexcept {
    try {
        led.set(drivers::LedState::error);
    } catch (...) {
    }
}

} // namespace

HardwareBoard::HardwareBoard(const BoardConfig& board) : camera_config_(board.camera) {
    if (board.sim && !board.sim->camera_only)
        throw std::logic_error("HardwareBoard on a simulated board");
    const GpioConfig& gpio = board.gpio;
#if FPP_HAVE_GPIOD
    led_ = std::make_unique<drivers::GpiodStatusLed>(
        line(board, "led_line", gpio.led_line, gpio.led_active_low));
#else
    not_built(drivers::DeviceKind::gpio, gpio.chip, "libgpiod");
#endif
    try {
#if FPP_HAVE_DRM
        drivers::DrmDisplaySettings display;
        display.card = board.display.card;
        // "auto" in the board file is the driver's empty request (first
        // connected connector, preferred mode).
        display.output.connector = board.display.connector == "auto" ? "" : board.display.connector;
        display.output.mode = board.display.mode == "auto" ? "" : board.display.mode;
        display_ = std::make_unique<drivers::DrmDisplay>(display);
#else
        not_built(drivers::DeviceKind::display, "display " + board.display.card, "libdrm");
#endif
#if FPP_HAVE_GPIOD
        trigger_ = std::make_unique<drivers::GpiodTriggerOutput>(
            line(board, "trigger_line", gpio.trigger_line, gpio.trigger_active_low));
        button_ = std::make_unique<drivers::GpiodButtonInput>(
            line(board, "button_line", gpio.button_line, gpio.button_active_low), gpio.debounce);
#endif
    } catch (...) {
        // The line is released with the board; most GPIO controllers keep
        // its level, so the error stays shown while the service restarts.
        show_error(*led_);
        throw;
    }
}

HardwareBoard::~HardwareBoard() = default;

std::unique_ptr<drivers::Camera> HardwareBoard::make_camera() const {
    if (camera_config_.driver != CameraDriver::aravis)
        throw std::logic_error("HardwareBoard: camera.driver sim without a sim section");
#if FPP_HAVE_ARAVIS
    return std::make_unique<drivers::AravisCamera>(camera_config_.device, camera_config_.settings);
#else
    not_built(drivers::DeviceKind::camera, "camera " + camera_config_.device, "aravis-0.8");
#endif
}

std::unique_ptr<drivers::Camera> HardwareBoard::reconnecting(std::unique_ptr<drivers::Camera> first,
                                                             const Logger& log) {
    return std::make_unique<ReconnectingCamera>([this] { return make_camera(); }, std::move(first),
                                                "camera " + camera_config_.device, log);
}

void HardwareBoard::open_camera(const Logger& log) {
    if (camera_)
        throw std::logic_error("HardwareBoard::open_camera: the camera is already open");
    try {
        camera_ = reconnecting(make_camera(), log);
    } catch (const drivers::DeviceError&) {
        show_error(*led_);
        throw;
    }
}

bool HardwareBoard::wait_for_camera(const Logger& log, const std::atomic<bool>& stop,
                                    const CameraWaitOptions& options) {
    if (camera_)
        throw std::logic_error("HardwareBoard::wait_for_camera: the camera is already open");
    auto first =
        scanner::wait_for_camera([this] { return make_camera(); }, *led_, log, stop, options)
            .camera;
    if (first)
        camera_ = reconnecting(std::move(first), log);
    return camera_ != nullptr;
}

Devices HardwareBoard::devices() {
    if (!camera_)
        throw std::logic_error("HardwareBoard::devices: the camera is not open");
    return Devices{*display_, *trigger_, *button_, *led_, *camera_, clock_};
}

} // namespace fpp::scanner
