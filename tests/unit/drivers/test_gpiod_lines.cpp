// The GPIO lines' failure without a chip. (Driving real lines needs a
// gpiochip: the virtual board; the button's debouncing is test_debounce.cpp.)

#include "test_support.hpp"

#include <gtest/gtest.h>

#if __has_include(<fpp/drivers/gpiod_lines.hpp>)

#include "fpp/drivers/device_error.hpp"
#include "fpp/drivers/gpiod_lines.hpp"

#include <chrono>
#include <functional>
#include <string>

namespace {

using fpp::drivers::DeviceError;
using fpp::drivers::GpioLineConfig;
using namespace std::chrono_literals;

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
