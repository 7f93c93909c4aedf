#include "fpp/sim/sim_display.hpp"

#include "fpp/drivers/device_error.hpp"

#include <algorithm>

namespace fpp::sim {

namespace {
const char* const kDevice = "sim display";
}

SimDisplay::SimDisplay(Size size, drivers::Clock& clock, std::chrono::nanoseconds flip_latency)
    : size_(size), clock_(clock), latency_ns_(flip_latency.count()) {}

SimDisplay::~SimDisplay() { restore(); }

void SimDisplay::prepare(const std::vector<Image<std::uint8_t>>& patterns) {
    if (pending_) throw drivers::DeviceError(kDevice, "prepare() while a flip is pending");
    for (const auto& p : patterns)
        if (p.size() != size_ || p.channels() != 1)
            throw drivers::DeviceError(kDevice, "pattern is not a 1-channel image of the projector size");
    patterns_ = patterns;
    restored_ = false;
}

void SimDisplay::show(std::size_t index) {
    if (index >= patterns_.size()) throw drivers::DeviceError(kDevice, "no buffer for pattern " + std::to_string(index));
    if (pending_) throw drivers::DeviceError(kDevice, "a page flip is already pending");
    if (fail_next_flip_) {
        fail_next_flip_ = false;
        throw drivers::DeviceError(kDevice, "page flip failed (injected)");
    }
    restored_ = false;
    pending_ = Scheduled{static_cast<int>(index), clock_.now_ns() + latency_ns_};
    schedule_.push_back(*pending_);
}

drivers::FlipEvent SimDisplay::wait_flip(std::chrono::milliseconds timeout) {
    if (!pending_) throw drivers::DeviceError(kDevice, "wait_flip() without a pending flip");
    const std::int64_t now = clock_.now_ns();
    const std::int64_t timeout_ns =
        std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count();
    const std::int64_t delivered = pending_->on_screen_ns - event_lead_ns_;
    if (lose_next_event_ || delivered - now > timeout_ns) {
        lose_next_event_ = false;
        pending_.reset(); // the flip itself still happens on schedule
        clock_.sleep_until_ns(now + timeout_ns);
        throw drivers::DeviceError(kDevice, "no flip event within " +
                                                std::to_string(timeout.count()) + " ms");
    }
    clock_.sleep_until_ns(delivered);
    drivers::FlipEvent event{static_cast<std::size_t>(pending_->index), ++sequence_, delivered};
    pending_.reset();
    flips_.push_back(event);
    if (hook_) hook_(event);
    return event;
}

void SimDisplay::restore() {
    if (restored_) return;
    restored_ = true;
    // A pending flip completes before the console comes back.
    const std::int64_t t =
        pending_ ? std::max(pending_->on_screen_ns, clock_.now_ns()) : clock_.now_ns();
    pending_.reset();
    schedule_.push_back({kNothing, t});
}

int SimDisplay::on_screen_at(std::int64_t t_ns) const {
    int index = kNothing;
    for (const Scheduled& s : schedule_) {
        if (s.on_screen_ns > t_ns) break;
        index = s.index;
    }
    return index;
}

} // namespace fpp::sim
