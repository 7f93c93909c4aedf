#pragma once
// The time base of a scan: CLOCK_MONOTONIC on hardware (the clock of DRM flip
// timestamps and GPIO edge events), a virtual clock in simulations so that
// tests of a 60 Hz projector do not wait for it.
#include <chrono>
#include <cstdint>
#include <thread>

namespace fpp::drivers {

class Clock {
public:
    virtual ~Clock() = default;
    // Nanoseconds on this clock's monotonic time line.
    virtual std::int64_t now_ns() = 0;
    // Blocks (or advances virtual time) until now_ns() >= t_ns.
    virtual void sleep_until_ns(std::int64_t t_ns) = 0;
    void sleep_for(std::chrono::nanoseconds d) { sleep_until_ns(now_ns() + d.count()); }
};

// std::chrono::steady_clock is CLOCK_MONOTONIC on Linux.
class SteadyClock final : public Clock {
public:
    std::int64_t now_ns() override {
        return std::chrono::duration_cast<std::chrono::nanoseconds>(
                   std::chrono::steady_clock::now().time_since_epoch())
            .count();
    }
    void sleep_until_ns(std::int64_t t_ns) override {
        std::this_thread::sleep_until(
            std::chrono::steady_clock::time_point(std::chrono::nanoseconds(t_ns)));
    }
};

} // namespace fpp::drivers
