#include "fpp/sim/sim_gpio.hpp"

#include <fpp/drivers/device_error.hpp>

namespace fpp::sim {

SimTrigger::SimTrigger(drivers::Clock& clock, std::function<void(std::int64_t)> wire)
    : clock_(clock), wire_(std::move(wire)) {}

void SimTrigger::pulse(std::chrono::microseconds width) {
    if (!connected_)
        throw drivers::DeviceError(drivers::DeviceKind::gpio, "sim trigger",
                                   "cannot open the chip: it went away");
    const std::int64_t rise = clock_.now_ns();
    pulses_.push(rise);
    if (wire_)
        wire_(rise);
    clock_.sleep_until_ns(rise +
                          std::chrono::duration_cast<std::chrono::nanoseconds>(width).count());
}

SimButton::SimButton(std::chrono::milliseconds debounce) : debounce_(debounce) {}

void SimButton::press(int bounces) {
    {
        std::lock_guard lock(mutex_);
        if (!connected_)
            return; // no chip, no edge
        const auto now = std::chrono::steady_clock::now();
        for (int i = 0; i <= bounces; ++i)
            edges_.push_back(now + std::chrono::microseconds(100 * i));
    }
    edge_.notify_all();
}

void SimButton::set_connected(bool connected) {
    {
        std::lock_guard lock(mutex_);
        connected_ = connected;
        if (!connected)
            edges_.clear();
    }
    edge_.notify_all();
}

void SimButton::require_connected_locked() const {
    if (!connected_)
        throw drivers::DeviceError(drivers::DeviceKind::gpio, "sim button",
                                   "reading an edge failed: the chip went away");
}

void SimButton::take_press_locked() {
    // The press's own edge always (with no debounce nothing else is within
    // it), then its bounces.
    const auto first = edges_.front();
    edges_.pop_front();
    while (!edges_.empty() && edges_.front() - first < debounce_)
        edges_.pop_front();
}

bool SimButton::wait_press(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    require_connected_locked();
    if (!edge_.wait_for(lock, timeout, [&] { return !edges_.empty() || !connected_; }))
        return false;
    require_connected_locked();
    take_press_locked();
    return true;
}

int SimButton::drain() {
    std::lock_guard lock(mutex_);
    require_connected_locked();
    int presses = 0;
    while (!edges_.empty()) {
        take_press_locked();
        ++presses;
    }
    return presses;
}

void SimLed::set(drivers::LedState state) {
    std::lock_guard lock(mutex_);
    history_.push(state);
}

std::vector<drivers::LedState> SimLed::history() const {
    std::lock_guard lock(mutex_);
    return history_.items();
}

void SimLed::limit_records(std::size_t limit) {
    std::lock_guard lock(mutex_);
    history_.set_limit(limit);
}

drivers::LedState SimLed::state() const {
    std::lock_guard lock(mutex_);
    return history_.back();
}

} // namespace fpp::sim
