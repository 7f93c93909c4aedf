#pragma once
// GPIO of the virtual scanner: a trigger line wired to the sim camera, a
// button whose presses tests inject (with bounces), an LED that records its
// states.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <vector>

#include <fpp/drivers/clock.hpp>
#include <fpp/drivers/gpio.hpp>

namespace fpp::sim {

class SimTrigger final : public drivers::TriggerOutput {
public:
    // `wire` is called at each rising edge with its clock time (the camera's
    // trigger input).
    SimTrigger(drivers::Clock& clock, std::function<void(std::int64_t)> wire);
    void pulse(std::chrono::microseconds width) override;
    // Rising-edge times of every pulse.
    const std::vector<std::int64_t>& pulses() const { return pulses_; }

private:
    drivers::Clock& clock_;
    std::function<void(std::int64_t)> wire_;
    std::vector<std::int64_t> pulses_;
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

private:
    // Removes one press (and its bounces) from the queue; the lock is held.
    void take_press_locked();
    std::chrono::milliseconds debounce_;
    std::mutex mutex_;
    std::condition_variable edge_;
    std::deque<std::chrono::steady_clock::time_point> edges_;
};

class SimLed final : public drivers::StatusLed {
public:
    void set(drivers::LedState state) override;
    std::vector<drivers::LedState> history() const;
    drivers::LedState state() const;

private:
    mutable std::mutex mutex_;
    std::vector<drivers::LedState> history_{drivers::LedState::off};
};

} // namespace fpp::sim
