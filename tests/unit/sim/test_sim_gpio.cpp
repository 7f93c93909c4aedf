// The virtual scanner's GPIO (fpp/sim/sim_gpio.hpp): the trigger line's
// pulses (rising edge on the wire, the clock moved on by the width), the
// button's presses with their bounces taken as one, the LED's states, and
// the chip going away and coming back.

#include "fpp/sim/sim_clock.hpp"
#include "fpp/sim/sim_gpio.hpp"

#include "fpp/drivers/device_error.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

using namespace fpp;
using namespace std::chrono_literals;

namespace {

// The DeviceError `f` throws: "device: what".
template <class F> std::string device_error(F&& f) {
    try {
        f();
    } catch (const drivers::DeviceError& e) {
        EXPECT_EQ(e.kind(), drivers::DeviceKind::gpio);
        return e.what();
    }
    return "no DeviceError";
}

TEST(SimTrigger, EachPulseRisesOnTheWireAndLastsItsWidth) {
    sim::VirtualClock clock(1'000'000);
    std::vector<std::int64_t> wire;
    sim::SimTrigger trigger(clock, [&](std::int64_t t) { wire.push_back(t); });
    trigger.pulse(100us);
    EXPECT_EQ(clock.now_ns(), 1'100'000);
    clock.advance(900'000);
    trigger.pulse(50us);
    EXPECT_EQ(clock.now_ns(), 2'050'000);
    EXPECT_EQ(trigger.pulses(), (std::vector<std::int64_t>{1'000'000, 2'000'000}));
    EXPECT_EQ(wire, trigger.pulses());
    // Nothing wired: pulses are recorded all the same.
    sim::SimTrigger loose(clock, nullptr);
    loose.pulse(10us);
    EXPECT_EQ(loose.pulses(), std::vector<std::int64_t>{2'050'000});
}

TEST(SimTrigger, WithoutItsChipAPulseIsADeviceErrorAndNoEdge) {
    sim::VirtualClock clock(0);
    int edges = 0;
    sim::SimTrigger trigger(clock, [&](std::int64_t) { ++edges; });
    trigger.set_connected(false);
    EXPECT_EQ(device_error([&] { trigger.pulse(100us); }),
              "sim trigger: cannot open the chip: it went away");
    EXPECT_EQ(edges, 0);
    EXPECT_TRUE(trigger.pulses().empty());
    EXPECT_EQ(clock.now_ns(), 0);
    trigger.set_connected(true);
    trigger.pulse(100us);
    EXPECT_EQ(edges, 1);
}

TEST(SimTrigger, RecordsOnlyTheNewestPulsesOnceLimited) {
    sim::VirtualClock clock(0);
    sim::SimTrigger trigger(clock, nullptr);
    trigger.limit_records(4);
    for (int i = 0; i < 5; ++i)
        trigger.pulse(1us);
    EXPECT_EQ(trigger.pulses(), (std::vector<std::int64_t>{2'000, 3'000, 4'000}));
}

TEST(SimButton, APressWithItsBouncesIsOnePress) {
    sim::SimButton button(30ms);
    EXPECT_EQ(button.drain(), 0);
    button.press(3); // four edges within 0.3 ms
    EXPECT_EQ(button.drain(), 1);
    EXPECT_EQ(button.drain(), 0);
}

TEST(SimButton, WaitPressTakesOnePress) {
    sim::SimButton button;
    EXPECT_FALSE(button.wait_press(0ms)); // nothing pressed
    button.press(2);
    EXPECT_TRUE(button.wait_press(0ms));
    EXPECT_FALSE(button.wait_press(0ms)); // its bounces went with it
}

TEST(SimButton, WithoutDebounceEveryEdgeIsAPress) {
    // debounce_ms: 0 in a board file: no edge is another's bounce.
    sim::SimButton button(0ms);
    button.press(2);
    EXPECT_EQ(button.drain(), 3);
    button.press();
    EXPECT_TRUE(button.wait_press(0ms));
    EXPECT_FALSE(button.wait_press(0ms));
}

TEST(SimButton, WithoutItsChipReadingIsADeviceErrorAndPressesAreLost) {
    sim::SimButton button;
    button.press();
    button.set_connected(false); // the press waiting is lost with the chip
    const std::string gone = "sim button: reading an edge failed: the chip went away";
    EXPECT_EQ(device_error([&] { button.wait_press(0ms); }), gone);
    EXPECT_EQ(device_error([&] { button.drain(); }), gone);
    button.press(); // on a chip that is away: no edge
    button.set_connected(true);
    EXPECT_EQ(button.drain(), 0);
    button.press();
    EXPECT_EQ(button.drain(), 1);
}

TEST(SimLed, RecordsEveryStateFromOff) {
    using drivers::LedState;
    sim::SimLed led;
    EXPECT_EQ(led.state(), LedState::off);
    led.set(LedState::ready);
    led.set(LedState::scanning);
    led.set(LedState::error);
    EXPECT_EQ(led.state(), LedState::error);
    EXPECT_EQ(led.history(), (std::vector<LedState>{LedState::off, LedState::ready,
                                                    LedState::scanning, LedState::error}));
    sim::SimLed limited;
    limited.limit_records(2);
    limited.set(LedState::ready);
    limited.set(LedState::scanning);
    EXPECT_EQ(limited.history(), (std::vector<LedState>{LedState::ready, LedState::scanning}));
    EXPECT_EQ(limited.state(), LedState::scanning);
}

} // namespace
