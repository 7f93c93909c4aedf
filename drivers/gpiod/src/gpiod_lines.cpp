// The three GPIO roles over a version-independent line that is requested
// again after its chip returns (reopening_line.hpp).
#include <fpp/drivers/gpiod_lines.hpp>

#include <fpp/drivers/debounce.hpp>
#include <fpp/drivers/device_error.hpp>

#include "reopening_line.hpp"

#include <condition_variable>
#include <mutex>
#include <thread>

namespace fpp::drivers {

// --- trigger ---------------------------------------------------------------

GpiodTriggerOutput::GpiodTriggerOutput(const GpioLineConfig& config, const std::string& consumer)
    : line_(std::make_unique<gpio_detail::ReopeningLine>(config, consumer, true, false)) {}

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
    gpio_detail::ReopeningLine line;
    Debouncer debouncer;
};

GpiodButtonInput::GpiodButtonInput(const GpioLineConfig& config, std::chrono::milliseconds debounce,
                                   const std::string& consumer)
    : state_(std::make_unique<State>(
          State{gpio_detail::ReopeningLine(config, consumer, false, false), Debouncer(debounce)})) {
}

GpiodButtonInput::~GpiodButtonInput() = default;

bool GpiodButtonInput::wait_press(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
        const auto left = deadline - std::chrono::steady_clock::now();
        const auto edge = state_->line.wait_edge(std::max(left, std::chrono::nanoseconds(0)));
        if (!edge)
            return false;
        if (state_->debouncer.edge(edge->timestamp_ns, edge->rising))
            return true;
    }
}

int GpiodButtonInput::drain() {
    int presses = 0;
    while (const auto edge = state_->line.wait_edge(std::chrono::nanoseconds(0)))
        presses += state_->debouncer.edge(edge->timestamp_ns, edge->rising) ? 1 : 0;
    return presses;
}

// --- LED -------------------------------------------------------------------

struct GpiodStatusLed::State {
    std::unique_ptr<gpio_detail::ReopeningLine> line;
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

    // The LED is best effort: the button and the trigger on the same chip
    // report a chip that went away; a lamp must not fail a scan.
    void set_quietly(bool lit) noexcept {
        try {
            line->set(lit);
        } catch (const DeviceError&) {
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
            set_quietly(lit);
            changed.wait_for(lock, half);
        }
    }
};

GpiodStatusLed::GpiodStatusLed(const GpioLineConfig& config, const std::string& consumer)
    : state_(std::make_unique<State>()) {
    state_->line = std::make_unique<gpio_detail::ReopeningLine>(config, consumer, true, false);
    state_->blinker = std::thread([s = state_.get()] { s->run(); });
}

GpiodStatusLed::~GpiodStatusLed() {
    {
        const std::lock_guard lock(state_->mutex);
        state_->stopping = true;
    }
    state_->changed.notify_all();
    state_->blinker.join();
    state_->set_quietly(false);
}

void GpiodStatusLed::set(LedState state) {
    {
        const std::lock_guard lock(state_->mutex);
        state_->state = state;
        if (State::half_period(state).count() == 0)
            state_->set_quietly(state == LedState::ready);
    }
    state_->changed.notify_all();
}

LedState GpiodStatusLed::state() const {
    const std::lock_guard lock(state_->mutex);
    return state_->state;
}

} // namespace fpp::drivers
