#pragma once
// The three GPIO roles of the scanner head. Each implementation holds its line
// request for its whole life (the lines stay claimed while the process runs).
// Active-low wiring is handled by the implementation: callers speak logical
// levels. Errors at run time throw DeviceError.
#include <chrono>

#include <fpp/enum_names.hpp>

namespace fpp::drivers {

// Camera trigger output: a positive (logical) pulse starts an exposure.
class TriggerOutput {
public:
    virtual ~TriggerOutput() = default;
    TriggerOutput(const TriggerOutput&) = delete;
    TriggerOutput& operator=(const TriggerOutput&) = delete;

    // Drive the line active for `width`, then inactive. Returns after the
    // falling edge.
    virtual void pulse(std::chrono::microseconds width) = 0;

protected:
    TriggerOutput() = default;
};

// The scan button: an edge event, debounced.
class ButtonInput {
public:
    virtual ~ButtonInput() = default;
    ButtonInput(const ButtonInput&) = delete;
    ButtonInput& operator=(const ButtonInput&) = delete;

    // Wait up to `timeout` for one debounced press. Returns true on a press,
    // false on timeout. Bounces within the debounce window count once.
    virtual bool wait_press(std::chrono::milliseconds timeout) = 0;

    // Discard presses already queued (e.g. those made during a scan).
    // Returns how many were discarded.
    virtual int drain() = 0;

protected:
    ButtonInput() = default;
};

enum class LedState { off, ready, scanning, error };
inline constexpr EnumName<LedState> kLedStateNames[] = {
    {LedState::off, "off"},
    {LedState::ready, "ready"},
    {LedState::scanning, "scanning"},
    {LedState::error, "error"},
};

// The status LED. How a state looks (steady, blinking) is the board's business.
// An implementation may keep set() from throwing (the hardware LED does: a
// scan must not fail for its lamp).
class StatusLed {
public:
    virtual ~StatusLed() = default;
    StatusLed(const StatusLed&) = delete;
    StatusLed& operator=(const StatusLed&) = delete;

    virtual void set(LedState state) = 0;

protected:
    StatusLed() = default;
};

// "off", "ready", "scanning", "error" (log lines).
inline const char* to_string(LedState state) {
    return name_of(kLedStateNames, state);
}

} // namespace fpp::drivers
