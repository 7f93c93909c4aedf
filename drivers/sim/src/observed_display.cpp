#include "fpp/sim/observed_display.hpp"

#include <algorithm>

namespace fpp::sim {

ObservedDisplay::ObservedDisplay(drivers::Display& display) : display_(display) {}

Size ObservedDisplay::size() const {
    return display_.size();
}

void ObservedDisplay::prepare(const std::vector<Image<std::uint8_t>>& patterns) {
    display_.prepare(patterns);
    patterns_ = patterns;
}

void ObservedDisplay::show(std::size_t index) {
    display_.show(index);
}

drivers::FlipEvent ObservedDisplay::wait_flip(std::chrono::milliseconds timeout) {
    const drivers::FlipEvent event = display_.wait_flip(timeout);
    const std::lock_guard lock(mutex_);
    flips_.push_back(event);
    return event;
}

void ObservedDisplay::restore() {
    display_.restore();
    const std::lock_guard lock(mutex_);
    flips_.clear(); // the projector is dark (or shows the console) again
}

int ObservedDisplay::on_screen_at(std::int64_t t_ns) const {
    const std::lock_guard lock(mutex_);
    // Events arrive in time order; the last one not after t_ns is on screen.
    const auto after = std::upper_bound(
        flips_.begin(), flips_.end(), t_ns,
        [](std::int64_t t, const drivers::FlipEvent& e) { return t < e.timestamp_ns; });
    if (after == flips_.begin())
        return kNothing;
    return static_cast<int>(std::prev(after)->index);
}

const Image<std::uint8_t>& ObservedDisplay::pattern(std::size_t index) const {
    return patterns_.at(index);
}

} // namespace fpp::sim
