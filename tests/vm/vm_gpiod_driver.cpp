// vm-gpiod: the scanner's GPIO driver itself (drivers/gpiod, built with the
// backend of the libgpiod it is compiled against) on the virtual ARM board's
// PL061, after vm-probe in the same boot (tests/vm/run_vm_probe.sh):
//   1. the trigger line (0) pulsed 200 times at 100 us, each pulse timed;
//   2. the LED line (1) set through its states, the blinker thread running;
//   3. the button line (3): a press waited for (the harness presses QEMU's
//      power button when it reads "vm-gpiod: press now"), then two presses
//      made while nobody reads the line: their four edges wait in the
//      kernel and drain() must count exactly 2 presses (the 2.x backend
//      reads them in one batch); then nothing is left (drain() 0, no press
//      within 300 ms);
//   4. the chip goes away (the PL061's driver unbound through sysfs) and
//      comes back (bound again): while away the trigger's pulse and the
//      button's wait fail with DeviceError naming the line, the LED's set
//      does not throw; once back (numbered anew while the old number is
//      held: found by its label) the trigger pulses, the LED is set and a
//      press is waited for, with the same objects.
// Prints "vm-gpiod: OK ..." lines with the figures, "vm-gpiod: FAIL ..." and
// exit 1 on the first failure.
#include <fpp/drivers/device_error.hpp>
#include <fpp/drivers/gpiod_lines.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace std::chrono_literals;
using fpp::drivers::GpioLineConfig;

GpioLineConfig line(unsigned int offset) {
    GpioLineConfig config;
    config.chip = "gpiochip0";
    config.offset = offset;
    config.field = "vm-gpiod line " + std::to_string(offset);
    return config;
}

// The PL061 of QEMU's virt machine, as its platform driver names it.
constexpr const char* kPl061 = "9030000.pl061";

bool write_sysfs(const char* file, const char* text) {
    std::ofstream out(file);
    out << text;
    out.flush();
    return static_cast<bool>(out);
}

std::string gpio_chips() {
    std::string names;
    for (const auto& entry : std::filesystem::directory_iterator("/dev"))
        if (entry.path().filename().string().rfind("gpiochip", 0) == 0)
            names += (names.empty() ? "" : " ") + entry.path().filename().string();
    return names.empty() ? "none" : names;
}

// The DeviceError text of `call`, or "" when it did not throw one.
template <class Call> std::string device_error_of(Call call) {
    try {
        call();
    } catch (const fpp::drivers::DeviceError& e) {
        return e.what();
    }
    return {};
}

void say(const char* text) {
    std::printf("vm-gpiod: %s\n", text);
    std::fflush(stdout);
}

int fail(const char* what) {
    std::printf("vm-gpiod: FAIL %s\n", what);
    return 1;
}

int run() {
    fpp::drivers::GpiodTriggerOutput trigger(line(0));
    fpp::drivers::GpiodStatusLed led(line(1));
    fpp::drivers::GpiodButtonInput button(line(3), 30ms);

    std::vector<double> pulse_us;
    for (int i = 0; i < 200; ++i) {
        const auto start = std::chrono::steady_clock::now();
        trigger.pulse(100us);
        pulse_us.push_back(
            std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start)
                .count());
    }
    std::sort(pulse_us.begin(), pulse_us.end());
    std::printf("vm-gpiod: OK trigger: %zu pulses of 100 us took median %.0f us, max %.0f us\n",
                pulse_us.size(), pulse_us[pulse_us.size() / 2], pulse_us.back());

    for (const auto state : {fpp::drivers::LedState::ready, fpp::drivers::LedState::scanning,
                             fpp::drivers::LedState::error, fpp::drivers::LedState::off}) {
        led.set(state);
        if (led.state() != state)
            return fail("led: the state set is not the state read");
        std::this_thread::sleep_for(300ms); // the blinker toggles the line meanwhile
    }
    say("OK led: ready, scanning, error, off");

    if (button.drain() != 0)
        return fail("button: a press before any was made");
    say("press now (1)");
    const auto start = std::chrono::steady_clock::now();
    if (!button.wait_press(20s))
        return fail("button: no press within 20 s");
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // Past the pulse's falling edge, so that the next presses start clean.
    std::this_thread::sleep_for(400ms);
    // A second apart: the harness's press follows the console line after
    // tens of ms, and QEMU's pulse lasts 100 ms.
    say("press now (2)");
    std::this_thread::sleep_for(1s);
    say("press now (3)");
    std::this_thread::sleep_for(1s);
    const int queued = button.drain();
    std::printf("vm-gpiod: button: first press after %.3f s, %d presses drained\n", waited, queued);
    if (queued != 2)
        return fail("button: drain() did not count the 2 queued presses");
    if (button.drain() != 0 || button.wait_press(300ms))
        return fail("button: a press left after drain()");
    say("OK button: 1 press waited for, 2 queued presses drained, none left");

    led.set(fpp::drivers::LedState::ready);
    if (!write_sysfs("/sys/bus/amba/drivers/pl061_gpio/unbind", kPl061))
        return fail("cannot unbind the PL061 (/sys/bus/amba/drivers/pl061_gpio/unbind)");
    std::printf("vm-gpiod: chip gone: /dev has %s\n", gpio_chips().c_str());
    const std::string pulse_gone = device_error_of([&] { trigger.pulse(100us); });
    const std::string button_gone = device_error_of([&] { button.wait_press(100ms); });
    const std::string pulse_still_gone = device_error_of([&] { trigger.pulse(100us); });
    const std::string led_gone = device_error_of([&] { led.set(fpp::drivers::LedState::error); });
    std::printf("vm-gpiod: chip gone: trigger '%s', button '%s', trigger again '%s'\n",
                pulse_gone.c_str(), button_gone.c_str(), pulse_still_gone.c_str());
    if (pulse_gone.find("gpiochip0 line 0 (vm-gpiod line 0): ") != 0 ||
        button_gone.find("gpiochip0 line 3 (vm-gpiod line 3): ") != 0 ||
        pulse_still_gone.find("cannot open the chip") == std::string::npos)
        return fail("chip gone: the trigger and the button did not both fail naming their line");
    if (!led_gone.empty())
        return fail(("chip gone: the LED threw: " + led_gone).c_str());
    if (!write_sysfs("/sys/bus/amba/drivers/pl061_gpio/bind", kPl061))
        return fail("cannot bind the PL061 again");
    std::printf("vm-gpiod: chip back: /dev has %s\n", gpio_chips().c_str());
    trigger.pulse(100us);
    led.set(fpp::drivers::LedState::ready);
    if (button.drain() != 0)
        return fail("chip back: a press before any was made");
    say("press now (4)");
    if (!button.wait_press(20s))
        return fail("chip back: no press within 20 s");
    say("OK chip gone and back: trigger, LED and button work again");
    return 0;
}

} // namespace

int main() {
    try {
        return run();
    } catch (const fpp::drivers::DeviceError& e) {
        std::printf("vm-gpiod: FAIL %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::printf("vm-gpiod: FAIL %s\n", e.what());
        return 1;
    }
}
