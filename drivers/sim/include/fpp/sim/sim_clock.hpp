#pragma once
// A virtual monotonic clock for the simulated scanner: sleeping advances time
// at once, so a scan at 60 Hz runs as fast as the renderer allows and timings
// are reproducible.
#include <atomic>
#include <cstdint>

#include <fpp/drivers/clock.hpp>

namespace fpp::sim {

class VirtualClock final : public drivers::Clock {
public:
    explicit VirtualClock(std::int64_t start_ns = 1'000'000'000) : now_(start_ns) {}
    std::int64_t now_ns() override { return now_.load(); }
    void sleep_until_ns(std::int64_t t_ns) override {
        std::int64_t now = now_.load();
        while (t_ns > now && !now_.compare_exchange_weak(now, t_ns)) {
        }
    }
    // Time spent by work outside sleeps (e.g. a frame read-out).
    void advance(std::int64_t ns) { now_.fetch_add(ns); }

private:
    std::atomic<std::int64_t> now_;
};

} // namespace fpp::sim
