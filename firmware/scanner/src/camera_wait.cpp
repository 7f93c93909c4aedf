#include "fpp/scanner/camera_wait.hpp"

#include "fpp/drivers/device_error.hpp"

#include <stdexcept>
#include <string>
#include <thread>

namespace fpp::scanner {

void CameraWaitOptions::validate() const {
    if (retry.count() <= 0)
        throw std::invalid_argument("CameraWaitOptions.retry must be positive");
    if (reminder < retry)
        throw std::invalid_argument("CameraWaitOptions.reminder must be at least retry");
}

namespace {

// Sleeps `total`, in slices, until then or until `stop` is set; false if
// stopped.
bool pause(std::chrono::milliseconds total, const std::atomic<bool>& stop) {
    const auto end = std::chrono::steady_clock::now() + total;
    constexpr auto slice = std::chrono::milliseconds(50);
    while (!stop.load()) {
        const auto now = std::chrono::steady_clock::now();
        if (now >= end)
            return true;
        std::this_thread::sleep_for(
            std::min<std::chrono::steady_clock::duration>(slice, end - now));
    }
    return false;
}

} // namespace

CameraWaitResult wait_for_camera(const CameraOpener& open, drivers::StatusLed& led,
                                 const Logger& log, const std::atomic<bool>& stop,
                                 const CameraWaitOptions& options) {
    options.validate();
    CameraWaitResult result;
    auto last_logged = std::chrono::steady_clock::time_point::min();
    while (!stop.load()) {
        try {
            result.camera = open();
            if (result.failed_attempts > 0)
                log.info("camera answered after " + std::to_string(result.failed_attempts) +
                         " failed attempt(s)");
            return result;
        } catch (const drivers::DeviceError& e) {
            ++result.failed_attempts;
            led.set(drivers::LedState::error);
            const auto now = std::chrono::steady_clock::now();
            if (result.failed_attempts == 1 || now - last_logged >= options.reminder) {
                log.error(std::string(e.what()) + "; waiting for it (attempt " +
                          std::to_string(result.failed_attempts) + ", again every " +
                          std::to_string(options.retry.count()) + " ms)");
                last_logged = now;
            }
        }
        if (!pause(options.retry, stop))
            break;
    }
    return result;
}

} // namespace fpp::scanner
