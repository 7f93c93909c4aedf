// The three GPIO roles over a version-independent line (gpio_line.hpp).
#include <fpp/drivers/gpiod_lines.hpp>

#include <fpp/drivers/debounce.hpp>
#include <fpp/drivers/device_error.hpp>

#include "gpio_line.hpp"

#include <condition_variable>
#include <mutex>
#include <thread>

namespace fpp::drivers {

// --- trigger ---------------------------------------------------------------

GpiodTriggerOutput::GpiodTriggerOutput(const GpioLineConfig& config, const std::string& consumer)
    : line_(gpio_detail::open_output_line(config, consumer, false)) {}

GpiodTriggerOutput::~GpiodTriggerOutput() = default;

void GpiodTriggerOutput::pulse(std::chrono::microseconds width) {
    line_->set(true);
    // A busy wait would be tighter, but camera trigger inputs need tens of
    // microseconds at least and the sleep keeps the core free.
    std::this_thread::sleep_for(width);
    line_->set(false);
}

// --- button ----------------------------------------------------------------

struct GpiodButtonInput::State {
    std::unique_ptr<gpio_detail::Line> line;
    Debouncer debouncer;
};

GpiodButtonInput::GpiodButtonInput(const GpioLineConfig& config, std::chrono::milliseconds debounce,
                                   const std::string& consumer)
    : state_(std::make_unique<State>(
          State{gpio_detail::open_edge_line(config, consumer), Debouncer(debounce)})) {}

GpiodButtonInput::~GpiodButtonInput() = default;

bool GpiodButtonInput::wait_press(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
        const auto left = deadline - std::chrono::steady_clock::now();
        const auto edge = state_->line->wait_edge(std::max(left, std::chrono::nanoseconds(0)));
        if (!edge)
            return false;
        if (state_->debouncer.edge(edge->timestamp_ns, edge->rising))
            return true;
    }
}

int GpiodButtonInput::drain() {
    int presses = 0;
    while (const auto edge = state_->line->wait_edge(std::chrono::nanoseconds(0)))
        presses += state_->debouncer.edge(edge->timestamp_ns, edge->rising) ? 1 : 0;
    return presses;
}

// --- LED -------------------------------------------------------------------

struct GpiodStatusLed::State {
    std::unique_ptr<gpio_detail::Line> line;
    std::mutex mutex;
    std::condition_variable changed;
    LedState state = LedState::off;
    bool stopping = false;
    std::thread blinker; // last: started after the members it uses

    // Half period of the blinking for a state; 0 = steady.
    static std::chrono::milliseconds half_period(LedState s) {
        switch (s) {
        case LedState::scanning:
            return std::chrono::milliseconds(125);
        case LedState::error:
            return std::chrono::milliseconds(500);
        default:
            return std::chrono::milliseconds(0);
        }
    }

    void run() {
        std::unique_lock lock(mutex);
        bool lit = false;
        while (!stopping) {
            const auto half = half_period(state);
            if (half.count() == 0) {
                changed.wait(lock);
                continue;
            }
            lit = !lit;
            try {
                line->set(lit);
            } catch (const DeviceError&) {
                // The LED is best effort; the scanner logs the error it shows.
            }
            changed.wait_for(lock, half);
        }
    }
};

GpiodStatusLed::GpiodStatusLed(const GpioLineConfig& config, const std::string& consumer)
    : state_(std::make_unique<State>()) {
    state_->line = gpio_detail::open_output_line(config, consumer, false);
    state_->blinker = std::thread([s = state_.get()] { s->run(); });
}

GpiodStatusLed::~GpiodStatusLed() {
    {
        const std::lock_guard lock(state_->mutex);
        state_->stopping = true;
    }
    state_->changed.notify_all();
    state_->blinker.join();
    try {
        state_->line->set(false);
    } catch (const DeviceError&) {
    }
}

void GpiodStatusLed::set(LedState state) {
    {
        const std::lock_guard lock(state_->mutex);
        state_->state = state;
        if (State::half_period(state).count() == 0)
            state_->line->set(state == LedState::ready);
    }
    state_->changed.notify_all();
}

LedState GpiodStatusLed::state() const {
    const std::lock_guard lock(state_->mutex);
    return state_->state;
}

} // namespace fpp::drivers
