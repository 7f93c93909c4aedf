#pragma once
// A hardware failure at run time: a device that vanished, timed out or
// returned something unusable. Distinct from fpp::InputError (bad config) so
// that the scan loop can put the LED in its error state and go back to idle.
#include <stdexcept>
#include <string>

namespace fpp::drivers {

// Which device failed: what the scan decides on (a camera fault is retried
// once; a display or GPIO fault is not).
enum class DeviceKind { camera, display, gpio };

class DeviceError : public std::runtime_error {
public:
    // device: a short name a person recognises ("display card0", "camera
    // 127.0.0.1", "gpiochip0 line 17"); what: what went wrong.
    DeviceError(DeviceKind kind, std::string device, const std::string& what)
        : std::runtime_error(device + ": " + what), kind_(kind), device_(std::move(device)) {}

    DeviceKind kind() const { return kind_; }
    const std::string& device() const { return device_; }

private:
    DeviceKind kind_;
    std::string device_;
};

} // namespace fpp::drivers
