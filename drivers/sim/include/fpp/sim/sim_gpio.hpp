#pragma once
// GPIO of the virtual scanner: a trigger line wired to the sim camera, a
// button whose presses tests inject (with bounces), an LED that records its
// states. Trigger and button can lose their chip (set_connected(false)):
// their calls then throw DeviceError as the libgpiod driver's do when a
// chip goes away, until it is back.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <vector>

#include <fpp/drivers/clock.hpp>
#include <fpp/drivers/gpio.hpp>
#include <fpp/sim/record_log.hpp>

namespace fpp::sim {

class SimTrigger final : public drivers::TriggerOutput {
public:
    // `wire` is called at each rising edge with its clock time (the camera's
    // trigger input).
    SimTrigger(drivers::Clock& clock, std::function<void(std::int64_t)> wire);
    void pulse(std::chrono::microseconds width) override;
    // False: pulse() throws DeviceError ("sim trigger: ...").
    void set_connected(bool connected) { connected_ = connected; }
    // Rising-edge times of every pulse.
    const std::vector<std::int64_t>& pulses() const { return pulses_.items(); }
    void limit_records(std::size_t limit) { pulses_.set_limit(limit); }

private:
    drivers::Clock& clock_;
    std::function<void(std::int64_t)> wire_;
    RecordLog<std::int64_t> pulses_;
    std::atomic<bool> connected_{true};
};

// Presses are queued edges; thread-safe (tests press from another thread).
// Debounce on the wall clock: edges within `debounce` of an accepted press
// are the same press.
class SimButton final : public drivers::ButtonInput {
public:
    explicit SimButton(std::chrono::milliseconds debounce = std::chrono::milliseconds(30));
    bool wait_press(std::chrono::milliseconds timeout) override;
    int drain() override;
    // One press plus `bounces` extra edges within a millisecond.
    void press(int bounces = 0);
    // False: wait_press() and drain() throw DeviceError ("sim button: ...");
    // presses made meanwhile are lost, as edges on a chip that is away.
    void set_connected(bool connected);

private:
    // Removes one press (and its bounces) from the queue; the lock is held.
    void take_press_locked();
    // DeviceError while the chip is away; the lock is held.
    void require_connected_locked() const;
    std::chrono::milliseconds debounce_;
    bool connected_ = true;
    std::mutex mutex_;
    std::condition_variable edge_;
    std::deque<std::chrono::steady_clock::time_point> edges_;
};

class SimLed final : public drivers::StatusLed {
public:
    SimLed() { history_.push(drivers::LedState::off); }
    void set(drivers::LedState state) override;
    // The states set, oldest first (the newest ones only, once limited).
    std::vector<drivers::LedState> history() const;
    drivers::LedState state() const;
    void limit_records(std::size_t limit);

private:
    mutable std::mutex mutex_;
    RecordLog<drivers::LedState> history_; // starts with off
};

} // namespace fpp::sim
