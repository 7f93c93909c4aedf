// ObservedDisplay: a display seen by the simulated camera through its flip
// events. Here the display underneath is the sim display, whose own schedule
// is the reference.
#include "fpp/sim/observed_display.hpp"
#include "fpp/sim/sim_clock.hpp"
#include "fpp/sim/sim_display.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <vector>

namespace {

using fpp::sim::ObservedDisplay;
using fpp::sim::Screen;
using fpp::sim::SimDisplay;
using namespace std::chrono_literals;

std::vector<fpp::Image<std::uint8_t>> patterns(fpp::Size size, int count) {
    std::vector<fpp::Image<std::uint8_t>> out;
    for (int i = 0; i < count; ++i)
        out.emplace_back(size, 1, static_cast<std::uint8_t>(40 * i + 10));
    return out;
}

} // namespace

TEST(ObservedDisplay, FollowsTheFlipEventsOfTheDisplayUnderneath) {
    fpp::sim::VirtualClock clock;
    SimDisplay display({64, 40}, clock, 10ms);
    ObservedDisplay observed(display);
    EXPECT_EQ(observed.size(), (fpp::Size{64, 40}));
    observed.prepare(patterns({64, 40}, 3));
    EXPECT_EQ(display.pattern_count(), 3u); // passed on
    EXPECT_EQ(observed.pattern(2).at(5, 5), 90);
    EXPECT_THROW(observed.pattern(3), std::out_of_range);

    const std::int64_t t0 = clock.now_ns();
    EXPECT_EQ(observed.on_screen_at(t0), Screen::kNothing);
    observed.show(0);
    const auto first = observed.wait_flip(100ms);
    EXPECT_EQ(first.index, 0u);
    observed.show(1);
    const auto second = observed.wait_flip(100ms);
    // Before, at and between the flips, as the display's own schedule says.
    for (const std::int64_t t :
         {t0, first.timestamp_ns - 1, first.timestamp_ns, second.timestamp_ns - 1,
          second.timestamp_ns, second.timestamp_ns + 1'000'000'000})
        EXPECT_EQ(observed.on_screen_at(t), display.on_screen_at(t)) << t - t0;
    EXPECT_EQ(observed.on_screen_at(second.timestamp_ns), 1);

    // A flip shown but not yet waited for is not seen: the observer knows
    // only what the display has reported.
    observed.show(2);
    EXPECT_EQ(observed.on_screen_at(second.timestamp_ns + 1'000'000'000), 1);
    observed.wait_flip(100ms);

    observed.restore();
    EXPECT_TRUE(display.restored());
    EXPECT_EQ(observed.on_screen_at(clock.now_ns()), Screen::kNothing);
}

TEST(ObservedDisplay, FailuresOfTheDisplayPassThrough) {
    fpp::sim::VirtualClock clock;
    SimDisplay display({64, 40}, clock, 10ms);
    ObservedDisplay observed(display);
    observed.prepare(patterns({64, 40}, 2));
    display.fail_next_flip();
    EXPECT_ANY_THROW(observed.show(0));
    display.lose_next_flip_event();
    observed.show(1);
    EXPECT_ANY_THROW(observed.wait_flip(50ms));
    EXPECT_EQ(observed.on_screen_at(clock.now_ns()), Screen::kNothing);
}
