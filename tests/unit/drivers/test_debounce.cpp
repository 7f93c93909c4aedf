// Button debouncing (fpp/drivers/debounce.hpp, the GPIO driver's): a press
// counts only after a quiet window; bounces and release chatter do not.

#include "test_support.hpp"

#include <gtest/gtest.h>

#if __has_include(<fpp/drivers/debounce.hpp>)

#include "fpp/drivers/debounce.hpp"

#include <chrono>
#include <cstdint>
#include <vector>

namespace {

using fpp::drivers::Debouncer;
using namespace std::chrono_literals;

constexpr std::int64_t kMs = 1'000'000;

struct TimedEdge {
    std::int64_t t_ms;
    bool press;
};

int presses(const std::vector<TimedEdge>& edges, std::chrono::milliseconds window = 20ms) {
    Debouncer debouncer(window);
    int count = 0;
    for (const auto& e : edges)
        count += debouncer.edge(e.t_ms * kMs, e.press) ? 1 : 0;
    return count;
}

TEST(Debouncer, CleanPressesCountOnce) {
    EXPECT_EQ(presses({{0, true}, {150, false}}), 1);
    EXPECT_EQ(presses({{0, true}, {150, false}, {400, true}, {520, false}}), 2);
}

TEST(Debouncer, ContactBounceOnPressCountsOnce) {
    // Press at 1000 ms with 4 ms of chatter, held, then released.
    EXPECT_EQ(presses({{1000, true},
                       {1001, false},
                       {1002, true},
                       {1003, false},
                       {1004, true},
                       {1300, false}}),
              1);
}

TEST(Debouncer, ReleaseChatterIsNoPress) {
    // The press is long done; releasing chatters into rising edges.
    EXPECT_EQ(
        presses({{0, true}, {500, false}, {502, true}, {503, false}, {506, true}, {507, false}}),
        1);
}

TEST(Debouncer, WindowBoundary) {
    // A press exactly one window after the last edge counts; one ns earlier not.
    Debouncer debouncer(20ms);
    EXPECT_TRUE(debouncer.edge(0, true));
    EXPECT_FALSE(debouncer.edge(10 * kMs, false));
    EXPECT_TRUE(debouncer.edge(30 * kMs, true));
    EXPECT_FALSE(debouncer.edge(40 * kMs, false));
    EXPECT_FALSE(debouncer.edge(60 * kMs - 1, true));
    debouncer.reset();
    EXPECT_TRUE(debouncer.edge(60 * kMs, true));
}

} // namespace

#else

TEST(Debouncer, NotBuilt) {
    if (fpp::test::in_ci())
        FAIL() << "fpp_gpiod is not linked to this test";
    GTEST_SKIP() << "the libgpiod driver is not built (libgpiod not found)";
}

#endif
