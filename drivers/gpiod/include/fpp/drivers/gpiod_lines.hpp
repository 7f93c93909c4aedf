#pragma once
// The scanner head's GPIO roles over libgpiod (character device /dev/gpiochipN).
// Each object requests its line when built and holds it while the chip is
// there; the scanner keeps them for the life of the process. Active-low
// wiring is set in the request, so callers and the kernel speak logical
// levels.
//
// A chip that goes away (its driver unbound, a module unloaded, a GPIO
// expander unplugged) fails the call that uses it with DeviceError, and the
// request is released. The next call requests the line again, on the chip
// found by the label it had when first opened: a chip that comes back is
// often numbered anew (gpiochip0 comes back as gpiochip1 while the old
// number is still held), its label stays. Until the chip is back each call
// fails with "cannot open the chip". The LED does not throw at run time
// (see GpiodStatusLed); the button and the trigger report the fault.
//
// Built against libgpiod 1.x (Debian 12) or 2.x (Debian 13, Raspberry Pi OS):
// the calls are confined to src/gpio_line_v1.cpp and src/gpio_line_v2.cpp
// behind an internal line interface, and behave the same (messages included).
#include <chrono>
#include <memory>
#include <string>

#include <fpp/drivers/gpio.hpp>

namespace fpp::drivers {

struct GpioLineConfig {
    std::string chip = "gpiochip0"; // name, number ("0"), label or /dev path
    unsigned int offset = 0;        // line offset on the chip
    bool active_low = false;
    // Who names the line, for error messages ("board.yaml gpio.led_line");
    // may be empty.
    std::string field;
};

namespace gpio_detail {
class ReopeningLine; // a line request made again after its chip returns (src/)
}

class GpiodTriggerOutput final : public TriggerOutput {
public:
    // Requests the line as an output, inactive. Throws DeviceError naming chip
    // and line ("gpiochip0 line 17") if the chip or line cannot be had.
    explicit GpiodTriggerOutput(const GpioLineConfig& config,
                                const std::string& consumer = "fpp-trigger");
    ~GpiodTriggerOutput() override;
    void pulse(std::chrono::microseconds width) override;

private:
    std::unique_ptr<gpio_detail::ReopeningLine> line_;
};

class GpiodButtonInput final : public ButtonInput {
public:
    // Requests both edges of the line; a logical rising edge is a press.
    // Presses closer than `debounce` to another edge are bounces (Debouncer).
    GpiodButtonInput(const GpioLineConfig& config, std::chrono::milliseconds debounce,
                     const std::string& consumer = "fpp-button");
    ~GpiodButtonInput() override;
    bool wait_press(std::chrono::milliseconds timeout) override;
    int drain() override;

private:
    struct State;
    std::unique_ptr<State> state_;
};

// A single-colour LED: off -> dark, ready -> lit, scanning -> blinking at
// 4 Hz, error -> blinking at 1 Hz (a thread of its own drives the blinking).
// Only its construction throws: at run time the LED is best effort (a scan
// does not fail for its lamp), a failed line is requested again at the next
// change or blink.
class GpiodStatusLed final : public StatusLed {
public:
    explicit GpiodStatusLed(const GpioLineConfig& config, const std::string& consumer = "fpp-led");
    ~GpiodStatusLed() override;
    void set(LedState state) override;
    LedState state() const;

private:
    struct State;
    std::unique_ptr<State> state_;
};

} // namespace fpp::drivers
