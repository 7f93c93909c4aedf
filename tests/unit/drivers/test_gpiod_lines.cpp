// Button debouncing, and the GPIO lines' failure without a chip. (Driving real
// lines needs a gpiochip: the virtual board.)

#include "test_support.hpp"

#include <gtest/gtest.h>

#if __has_include(<fpp/drivers/gpiod_lines.hpp>)

#include "fpp/drivers/debounce.hpp"
#include "fpp/drivers/device_error.hpp"
#include "fpp/drivers/gpiod_lines.hpp"

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace {

using fpp::drivers::Debouncer;
using fpp::drivers::DeviceError;
using fpp::drivers::GpioLineConfig;
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

void expect_missing_chip(const std::function<void(const GpioLineConfig&)>& open) {
    GpioLineConfig config;
    config.chip = "/nonexistent/gpiochip7";
    config.offset = 17;
    try {
        open(config);
        FAIL() << "opened a line on a chip that does not exist";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.device(), "/nonexistent/gpiochip7 line 17");
        EXPECT_EQ(e.kind(), fpp::drivers::DeviceKind::gpio);
        EXPECT_NE(std::string(e.what()).find("cannot open the chip"), std::string::npos)
            << e.what();
    }
}

TEST(GpiodLines, MissingChipIsADeviceErrorNamingChipAndLine) {
    expect_missing_chip([](const GpioLineConfig& c) { fpp::drivers::GpiodTriggerOutput t(c); });
    expect_missing_chip([](const GpioLineConfig& c) { fpp::drivers::GpiodButtonInput b(c, 20ms); });
    expect_missing_chip([](const GpioLineConfig& c) { fpp::drivers::GpiodStatusLed l(c); });
    // By name too (lookup through /dev).
    try {
        GpioLineConfig config;
        config.chip = "gpiochip99";
        config.offset = 3;
        fpp::drivers::GpiodTriggerOutput trigger(config);
        FAIL() << "gpiochip99 exists here";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.device(), "gpiochip99 line 3");
    }
}

TEST(GpiodLines, ChipNamedByNumberOrLabelThatIsNotThereIsADeviceError) {
    // libgpiod 1.x looks a chip up by number and label itself; the 2.x
    // backend does it by hand and must fail the same way.
    for (const std::string chip : {"99", "no-such-label"}) {
        GpioLineConfig config;
        config.chip = chip;
        config.offset = 2;
        try {
            fpp::drivers::GpiodButtonInput button(config, 20ms);
            FAIL() << "chip '" << chip << "' exists here";
        } catch (const DeviceError& e) {
            EXPECT_EQ(e.device(), chip + " line 2");
            EXPECT_NE(std::string(e.what()).find("cannot open the chip"), std::string::npos)
                << e.what();
        }
    }
}

TEST(GpiodLines, ANonGpioDeviceIsADeviceError) {
    GpioLineConfig config;
    config.chip = "/dev/null";
    EXPECT_THROW(fpp::drivers::GpiodTriggerOutput trigger(config), DeviceError);
}

} // namespace

#else

TEST(GpiodLines, NotBuilt) {
    if (fpp::test::in_ci())
        FAIL() << "fpp_gpiod is not linked to this test";
    GTEST_SKIP() << "the libgpiod driver is not built (libgpiod not found)";
}

#endif
