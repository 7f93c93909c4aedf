#include "fpp/sim/sim_display.hpp"

#include "fpp/drivers/device_error.hpp"

#include <algorithm>
#include <iterator>

namespace fpp::sim {

namespace {
const char* const kDevice = "sim display";
}

SimDisplay::SimDisplay(Size size, drivers::Clock& clock, std::chrono::nanoseconds flip_latency)
    : size_(size), clock_(clock), latency_ns_(flip_latency.count()) {}

SimDisplay::~SimDisplay() {
    restore();
}

void SimDisplay::prepare(const std::vector<Image<std::uint8_t>>& patterns) {
    if (pending_)
        throw drivers::DeviceError(drivers::DeviceKind::display, kDevice,
                                   "prepare() while a flip is pending");
    for (const auto& p : patterns)
        if (p.size() != size_ || p.channels() != 1)
            throw drivers::DeviceError(drivers::DeviceKind::display, kDevice,
                                       "pattern is not a 1-channel image of the projector size");
    patterns_ = patterns;
    restored_ = false;
}

void SimDisplay::show(std::size_t index) {
    if (index >= patterns_.size())
        throw drivers::DeviceError(drivers::DeviceKind::display, kDevice,
                                   "no buffer for pattern " + std::to_string(index));
    if (pending_)
        throw drivers::DeviceError(drivers::DeviceKind::display, kDevice,
                                   "a page flip is already pending");
    if (!connected_)
        throw drivers::DeviceError(drivers::DeviceKind::display, kDevice,
                                   "page flip refused: the output is disconnected");
    if (fail_next_flip_) {
        fail_next_flip_ = false;
        throw drivers::DeviceError(drivers::DeviceKind::display, kDevice,
                                   "page flip failed (injected)");
    }
    restored_ = false;
    pending_ = Scheduled{static_cast<int>(index), clock_.now_ns() + latency_ns_};
    schedule_.push(*pending_);
}

drivers::FlipEvent SimDisplay::wait_flip(std::chrono::milliseconds timeout) {
    if (!pending_)
        throw drivers::DeviceError(drivers::DeviceKind::display, kDevice,
                                   "wait_flip() without a pending flip");
    const std::int64_t now = clock_.now_ns();
    const std::int64_t timeout_ns =
        std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count();
    const std::int64_t delivered = pending_->on_screen_ns - event_lead_ns_;
    if (lose_next_event_ || delivered - now > timeout_ns) {
        lose_next_event_ = false;
        pending_.reset(); // the flip itself still happens on schedule
        clock_.sleep_until_ns(now + timeout_ns);
        throw drivers::DeviceError(drivers::DeviceKind::display, kDevice,
                                   "no flip event within " + std::to_string(timeout.count()) +
                                       " ms");
    }
    clock_.sleep_until_ns(delivered);
    drivers::FlipEvent event{static_cast<std::size_t>(pending_->index), ++sequence_, delivered};
    pending_.reset();
    flips_.push(event);
    if (hook_)
        hook_(event);
    return event;
}

void SimDisplay::restore() {
    if (restored_)
        return;
    restored_ = true;
    // A pending flip completes before the console comes back.
    const std::int64_t t =
        pending_ ? std::max(pending_->on_screen_ns, clock_.now_ns()) : clock_.now_ns();
    pending_.reset();
    schedule_.push({kNothing, t});
}

int SimDisplay::on_screen_at(std::int64_t t_ns) const {
    // The last flip on screen at t_ns (the schedule is chronological).
    const auto& s = schedule_.items();
    const auto after =
        std::upper_bound(s.begin(), s.end(), t_ns, [](std::int64_t t, const Scheduled& entry) {
            return t < entry.on_screen_ns;
        });
    return after == s.begin() ? kNothing : std::prev(after)->index;
}

} // namespace fpp::sim
