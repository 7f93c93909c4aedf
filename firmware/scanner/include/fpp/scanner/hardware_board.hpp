#pragma once
// A hardware board (a board file without a sim section): the projector
// through DRM/KMS, trigger, button and LED lines through libgpiod, the camera
// through Aravis, on the steady clock. Each device is opened once and held
// for the life of the board.
#include <memory>

#include <fpp/drivers/camera.hpp>
#include <fpp/drivers/clock.hpp>
#include <fpp/drivers/display.hpp>
#include <fpp/drivers/gpio.hpp>
#include <fpp/scanner/board_config.hpp>
#include <fpp/scanner/scanner.hpp>

namespace fpp::scanner {

class HardwareBoard {
public:
    // Opens the LED line first (so that a later failure can be shown), then
    // the display, the trigger and button lines and, with `with_camera`, the
    // camera. Throws DeviceError naming the device that cannot be had, or a
    // driver that is not built into this binary; std::logic_error for a sim
    // board other than a camera_only one.
    explicit HardwareBoard(const BoardConfig& board, bool with_camera = true);
    ~HardwareBoard();
    HardwareBoard(const HardwareBoard&) = delete;
    HardwareBoard& operator=(const HardwareBoard&) = delete;

    // All devices; only for a board opened with its camera.
    Devices devices();
    drivers::Display& display() { return *display_; }
    drivers::TriggerOutput& trigger() { return *trigger_; }
    drivers::ButtonInput& button() { return *button_; }
    drivers::StatusLed& led() { return *led_; }
    drivers::Clock& clock() { return clock_; }

private:
    drivers::SteadyClock clock_;
    std::unique_ptr<drivers::StatusLed> led_;
    std::unique_ptr<drivers::Display> display_;
    std::unique_ptr<drivers::TriggerOutput> trigger_;
    std::unique_ptr<drivers::ButtonInput> button_;
    std::unique_ptr<drivers::Camera> camera_;
};

} // namespace fpp::scanner
