#pragma once
// A hardware failure at run time: a device that vanished, timed out or
// returned something unusable. Distinct from fpp::InputError (bad config) so
// that the scan loop can put the LED in its error state and go back to idle.
#include <stdexcept>
#include <string>

namespace fpp::drivers {

class DeviceError : public std::runtime_error {
public:
    // device: a short name a person recognises ("display card0", "camera
    // 127.0.0.1", "gpiochip0 line 17"); what: what went wrong.
    DeviceError(std::string device, const std::string& what)
        : std::runtime_error(device + ": " + what), device_(std::move(device)) {}

    const std::string& device() const { return device_; }

private:
    std::string device_;
};

} // namespace fpp::drivers
