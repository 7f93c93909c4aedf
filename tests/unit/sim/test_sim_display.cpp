// The virtual scanner's projector (fpp/sim/sim_display.hpp): a flip
// completes one latency after show() on the board's clock, waited for or
// not; what is on screen at any time; the refusals of the Display contract;
// and the fault hooks (a failed or lost flip, events that arrive early, the
// cable out).

#include "fpp/sim/sim_clock.hpp"
#include "fpp/sim/sim_display.hpp"

#include "fpp/drivers/device_error.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

using namespace fpp;
using namespace std::chrono_literals;
using sim::Screen;

namespace {

constexpr Size kProjector{64, 40};
constexpr std::int64_t kMs = 1'000'000;

std::vector<Image<std::uint8_t>> patterns(int count, Size size = kProjector) {
    std::vector<Image<std::uint8_t>> out;
    for (int i = 0; i < count; ++i)
        out.emplace_back(size, 1, static_cast<std::uint8_t>(50 * i + 5));
    return out;
}

// The DeviceError `f` throws: "sim display: what".
template <class F> std::string device_error(F&& f) {
    try {
        f();
    } catch (const drivers::DeviceError& e) {
        EXPECT_EQ(e.kind(), drivers::DeviceKind::display);
        EXPECT_EQ(e.device(), "sim display");
        return e.what();
    }
    return "no DeviceError";
}

struct Board {
    sim::VirtualClock clock{1'000 * kMs};
    sim::SimDisplay display{kProjector, clock, 10ms};
    Board() { display.prepare(patterns(3)); }
};

TEST(SimDisplay, AFlipIsOnScreenOneLatencyAfterShow) {
    Board b;
    EXPECT_EQ(b.display.size(), kProjector);
    EXPECT_EQ(b.display.pattern_count(), 3u);
    EXPECT_EQ(b.display.pattern(2).at(0, 0), 105);
    const std::int64_t t0 = b.clock.now_ns();
    EXPECT_EQ(b.display.on_screen_at(t0), Screen::kNothing);
    b.display.show(1);
    // On schedule whether or not anybody waits.
    EXPECT_EQ(b.display.on_screen_at(t0 + 10 * kMs - 1), Screen::kNothing);
    EXPECT_EQ(b.display.on_screen_at(t0 + 10 * kMs), 1);
    const drivers::FlipEvent first = b.display.wait_flip(100ms);
    EXPECT_EQ(first.index, 1u);
    EXPECT_EQ(first.sequence, 1u);
    EXPECT_EQ(first.timestamp_ns, t0 + 10 * kMs);
    EXPECT_EQ(b.clock.now_ns(), t0 + 10 * kMs); // waited on the board's clock
    b.clock.advance(5 * kMs);
    b.display.show(2);
    const drivers::FlipEvent second = b.display.wait_flip(100ms);
    EXPECT_EQ(second.index, 2u);
    EXPECT_EQ(second.sequence, 2u);
    EXPECT_EQ(second.timestamp_ns, t0 + 25 * kMs);
    EXPECT_EQ(b.display.on_screen_at(t0 + 25 * kMs - 1), 1);
    EXPECT_EQ(b.display.on_screen_at(t0 + 25 * kMs), 2);
    EXPECT_EQ(b.display.on_screen_at(t0 + 1'000'000 * kMs), 2);
    ASSERT_EQ(b.display.flips().size(), 2u);
    EXPECT_EQ(b.display.flips()[1].timestamp_ns, second.timestamp_ns);
}

TEST(SimDisplay, RefusesWhatTheDisplayContractForbids) {
    Board b;
    EXPECT_EQ(device_error([&] { b.display.show(3); }), "sim display: no buffer for pattern 3");
    EXPECT_EQ(device_error([&] { b.display.wait_flip(10ms); }),
              "sim display: wait_flip() without a pending flip");
    b.display.show(0);
    EXPECT_EQ(device_error([&] { b.display.show(1); }),
              "sim display: a page flip is already pending");
    EXPECT_EQ(device_error([&] { b.display.prepare(patterns(2)); }),
              "sim display: prepare() while a flip is pending");
    b.display.wait_flip(100ms);
    const std::string wrong = "sim display: pattern is not a 1-channel image of the projector size";
    EXPECT_EQ(device_error([&] { b.display.prepare(patterns(2, {32, 40})); }), wrong);
    EXPECT_EQ(device_error([&] { b.display.prepare({Image<std::uint8_t>(kProjector, 3)}); }),
              wrong);
    EXPECT_EQ(b.display.pattern_count(), 3u); // the earlier patterns kept
}

TEST(SimDisplay, AnInjectedFailureFailsOneShow) {
    Board b;
    b.display.fail_next_flip();
    EXPECT_EQ(device_error([&] { b.display.show(0); }), "sim display: page flip failed (injected)");
    b.display.show(0);
    EXPECT_EQ(b.display.wait_flip(100ms).index, 0u);
}

TEST(SimDisplay, WithTheCableOutEveryShowFails) {
    Board b;
    b.display.set_connected(false);
    for (int i = 0; i < 2; ++i)
        EXPECT_EQ(device_error([&] { b.display.show(0); }),
                  "sim display: page flip refused: the output is disconnected");
    b.display.set_connected(true);
    b.display.show(0);
    EXPECT_EQ(b.display.wait_flip(100ms).sequence, 1u);
}

TEST(SimDisplay, ALateOrLostEventTimesOutButTheFlipHappens) {
    sim::VirtualClock clock(0);
    sim::SimDisplay display(kProjector, clock, 50ms);
    display.prepare(patterns(2));
    display.show(1);
    EXPECT_EQ(device_error([&] { display.wait_flip(20ms); }),
              "sim display: no flip event within 20 ms");
    EXPECT_EQ(clock.now_ns(), 20 * kMs); // the whole timeout waited
    EXPECT_EQ(display.on_screen_at(50 * kMs), 1);
    EXPECT_TRUE(display.flips().empty());

    display.lose_next_flip_event();
    display.show(0);
    EXPECT_EQ(device_error([&] { display.wait_flip(100ms); }),
              "sim display: no flip event within 100 ms");
    EXPECT_EQ(clock.now_ns(), 120 * kMs);
    EXPECT_EQ(display.on_screen_at(70 * kMs - 1), 1);
    EXPECT_EQ(display.on_screen_at(70 * kMs), 0);
    display.show(1); // the next event arrives again
    EXPECT_EQ(display.wait_flip(100ms).timestamp_ns, 170 * kMs);
}

TEST(SimDisplay, EventsThatArriveEarlyAreStampedEarly) {
    Board b;
    b.display.set_event_lead(3ms);
    const std::int64_t t0 = b.clock.now_ns();
    b.display.show(2);
    const drivers::FlipEvent e = b.display.wait_flip(100ms);
    EXPECT_EQ(e.timestamp_ns, t0 + 7 * kMs);
    // The pattern is not on screen yet when its event says it is.
    EXPECT_EQ(b.display.on_screen_at(e.timestamp_ns), Screen::kNothing);
    EXPECT_EQ(b.display.on_screen_at(t0 + 10 * kMs), 2);
}

TEST(SimDisplay, RestoreBlanksAfterAPendingFlipAndIsIdempotent) {
    Board b;
    const std::int64_t t0 = b.clock.now_ns();
    b.display.show(0);
    b.display.wait_flip(100ms);
    b.display.show(1);
    b.display.restore(); // the pending flip completes, then the console
    EXPECT_TRUE(b.display.restored());
    EXPECT_EQ(b.display.on_screen_at(t0 + 20 * kMs - 1), 0);
    EXPECT_EQ(b.display.on_screen_at(t0 + 20 * kMs), Screen::kNothing);
    b.display.restore();
    EXPECT_EQ(device_error([&] { b.display.wait_flip(10ms); }),
              "sim display: wait_flip() without a pending flip");
    b.display.show(2); // shown again after a restore
    EXPECT_FALSE(b.display.restored());
}

TEST(SimDisplay, TheFlipHookSeesEveryDeliveredEvent) {
    Board b;
    std::vector<std::size_t> seen;
    b.display.on_flip([&](const drivers::FlipEvent& e) { seen.push_back(e.index); });
    for (const std::size_t i : {2u, 0u, 1u}) {
        b.display.show(i);
        b.display.wait_flip(100ms);
    }
    EXPECT_EQ(seen, (std::vector<std::size_t>{2, 0, 1}));
    b.display.limit_records(2);
    b.display.show(0);
    b.display.wait_flip(100ms);
    ASSERT_EQ(b.display.flips().size(), 2u);
    EXPECT_EQ(b.display.flips().back().sequence, 4u);
}

} // namespace
