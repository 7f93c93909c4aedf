#pragma once
// A hardware board (a board file without a sim section): the projector
// through DRM/KMS, trigger, button and LED lines through libgpiod, the camera
// through Aravis, on the steady clock. Each device is opened once and held
// for the life of the board; the camera, which a cable or a power cycle can
// take away, is opened again when it comes back (ReconnectingCamera).
#include <atomic>
#include <memory>

#include <fpp/drivers/camera.hpp>
#include <fpp/drivers/clock.hpp>
#include <fpp/drivers/display.hpp>
#include <fpp/drivers/gpio.hpp>
#include <fpp/scanner/board_config.hpp>
#include <fpp/scanner/camera_wait.hpp>
#include <fpp/scanner/scanner.hpp>

namespace fpp::scanner {

class HardwareBoard {
public:
    // Opens the LED line first (so that a later failure can be shown: the
    // LED is set to error before the exception leaves), then the display,
    // the trigger and the button lines. Throws DeviceError naming the device
    // that cannot be had, or a driver that is not built into this binary;
    // std::logic_error for a sim board other than a camera_only one.
    explicit HardwareBoard(const BoardConfig& board);
    ~HardwareBoard();
    HardwareBoard(const HardwareBoard&) = delete;
    HardwareBoard& operator=(const HardwareBoard&) = delete;

    // Opens the board's camera, once. Throws DeviceError as the constructor
    // (the LED set to error). `log` takes the camera's losses and returns.
    void open_camera(const Logger& log);
    // Opens the board's camera, waiting for it while it does not answer
    // (wait_for_camera): false if `stop` was set first.
    bool wait_for_camera(const Logger& log, const std::atomic<bool>& stop,
                         const CameraWaitOptions& options = {});

    // All devices; only once the camera is open.
    Devices devices();
    drivers::Display& display() { return *display_; }
    drivers::TriggerOutput& trigger() { return *trigger_; }
    drivers::ButtonInput& button() { return *button_; }
    drivers::StatusLed& led() { return *led_; }
    drivers::Clock& clock() { return clock_; }

private:
    std::unique_ptr<drivers::Camera> make_camera() const;
    std::unique_ptr<drivers::Camera> reconnecting(std::unique_ptr<drivers::Camera> first,
                                                  const Logger& log);

    CameraConfig camera_config_;
    drivers::SteadyClock clock_;
    std::unique_ptr<drivers::StatusLed> led_;
    std::unique_ptr<drivers::Display> display_;
    std::unique_ptr<drivers::TriggerOutput> trigger_;
    std::unique_ptr<drivers::ButtonInput> button_;
    std::unique_ptr<drivers::Camera> camera_;
};

} // namespace fpp::scanner
