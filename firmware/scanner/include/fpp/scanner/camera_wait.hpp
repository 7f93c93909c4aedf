#pragma once
// A camera that does not answer when the scanner starts as a service (a GigE
// camera still booting or getting its address, a cable out): the scanner
// waits for it with the LED in its error state and opens it as soon as it
// answers, instead of exiting and leaving the service manager to give up.
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>

#include <fpp/drivers/camera.hpp>
#include <fpp/drivers/gpio.hpp>
#include <fpp/scanner/log.hpp>

namespace fpp::scanner {

struct CameraWaitOptions {
    // Pause between two attempts to open the camera.
    std::chrono::milliseconds retry{5000};
    // The error is logged at the first failed attempt, then again (with the
    // attempts so far) at most this often, so that the journal keeps the
    // reason without a line per attempt.
    std::chrono::milliseconds reminder{60000};

    // Throws std::invalid_argument naming the field.
    void validate() const;
};

struct CameraWaitResult {
    std::unique_ptr<drivers::Camera> camera; // null when stopped first
    int failed_attempts = 0;
};

using CameraOpener = std::function<std::unique_ptr<drivers::Camera>()>;

// Calls `open` until it returns a camera or `stop` is set (checked at least
// every 50 ms while waiting). A DeviceError from `open` is the camera not
// answering (or refusing a setting: the log says which): logged, the LED
// set to error, another attempt after options.retry. Other exceptions
// propagate.
CameraWaitResult wait_for_camera(const CameraOpener& open, drivers::StatusLed& led,
                                 const Logger& log, const std::atomic<bool>& stop,
                                 const CameraWaitOptions& options = {});

} // namespace fpp::scanner
