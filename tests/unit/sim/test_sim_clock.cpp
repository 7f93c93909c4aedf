// The virtual clock of the simulated scanner (fpp/sim/sim_clock.hpp):
// sleeping moves time on at once and never back, work outside sleeps
// advances it, and threads sleeping at once leave it at the latest wake.

#include "fpp/sim/sim_clock.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>
#include <vector>

using fpp::sim::VirtualClock;

namespace {

TEST(VirtualClock, StartsWhereItIsToldOneSecondByDefault) {
    VirtualClock clock;
    EXPECT_EQ(clock.now_ns(), 1'000'000'000);
    VirtualClock other(42);
    EXPECT_EQ(other.now_ns(), 42);
}

TEST(VirtualClock, SleepingJumpsToTheWakeTimeAndNeverBack) {
    VirtualClock clock(1000);
    clock.sleep_until_ns(5000);
    EXPECT_EQ(clock.now_ns(), 5000);
    clock.sleep_until_ns(3000); // in the past: no change
    EXPECT_EQ(clock.now_ns(), 5000);
    clock.sleep_until_ns(5000);
    EXPECT_EQ(clock.now_ns(), 5000);
    clock.advance(250); // a frame's read-out
    EXPECT_EQ(clock.now_ns(), 5250);
    clock.sleep_until_ns(6000);
    EXPECT_EQ(clock.now_ns(), 6000);
}

TEST(VirtualClock, ThreadsSleepingAtOnceLeaveItAtTheLatestWake) {
    VirtualClock clock(0);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&clock, t] {
            for (std::int64_t i = 0; i < 10'000; ++i)
                clock.sleep_until_ns(i * 4 + t);
        });
    for (auto& thread : threads)
        thread.join();
    EXPECT_EQ(clock.now_ns(), 9'999 * 4 + 3);
    // advance() from several threads: every nanosecond counted.
    threads.clear();
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&clock] {
            for (int i = 0; i < 10'000; ++i)
                clock.advance(1);
        });
    for (auto& thread : threads)
        thread.join();
    EXPECT_EQ(clock.now_ns(), 9'999 * 4 + 3 + 40'000);
}

} // namespace
