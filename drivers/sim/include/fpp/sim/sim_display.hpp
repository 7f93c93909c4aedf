#pragma once
// The projector of the virtual scanner behind fpp::drivers::Display. It keeps
// the schedule of what is on screen: a flip queued by show() completes
// `flip_latency` later (one 60 Hz refresh by default) whether or not anybody
// waits for it, and on_screen_at(t) tells which pattern a camera exposing at
// time t sees. Fault hooks let tests break it.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <fpp/drivers/clock.hpp>
#include <fpp/drivers/display.hpp>
#include <fpp/sim/record_log.hpp>
#include <fpp/sim/screen.hpp>

namespace fpp::sim {

class SimDisplay final : public drivers::Display, public Screen {
public:
    // Nothing on screen (kNothing) until the first flip completes.

    SimDisplay(Size size, drivers::Clock& clock,
               std::chrono::nanoseconds flip_latency = std::chrono::nanoseconds(16'666'667));
    ~SimDisplay() override;

    Size size() const override { return size_; }
    void prepare(const std::vector<Image<std::uint8_t>>& patterns) override;
    void show(std::size_t index) override;
    drivers::FlipEvent wait_flip(std::chrono::milliseconds timeout) override;
    void restore() override;

    // --- simulation side ---
    // Pattern index on screen at time t_ns (clock time), kNothing for none.
    int on_screen_at(std::int64_t t_ns) const override;
    // The prepared pattern image (projector size, 8-bit).
    const Image<std::uint8_t>& pattern(std::size_t index) const override {
        return patterns_.at(index);
    }
    std::size_t pattern_count() const { return patterns_.size(); }
    // Every flip event delivered, in order.
    // (The newest ones only, once limited.)
    const std::vector<drivers::FlipEvent>& flips() const { return flips_.items(); }
    void limit_records(std::size_t limit) {
        flips_.set_limit(limit);
        schedule_.set_limit(limit);
    }
    bool restored() const { return restored_; }

    // Faults: the next show() fails; the next flip completes but its event is
    // never delivered (wait_flip times out); every event arrives (and is
    // stamped) `lead` before the flip is really on screen, as a display whose
    // events lie would.
    void fail_next_flip() { fail_next_flip_ = true; }
    void lose_next_flip_event() { lose_next_event_ = true; }
    // The projector's cable out (false) and back in (true): while it is out
    // every show() fails, as a page flip on a connector gone does.
    void set_connected(bool connected) { connected_ = connected; }
    void set_event_lead(std::chrono::nanoseconds lead) { event_lead_ns_ = lead.count(); }
    // Called with each delivered event (tests inject button presses from it).
    void on_flip(std::function<void(const drivers::FlipEvent&)> hook) { hook_ = std::move(hook); }

private:
    struct Scheduled {
        int index;
        std::int64_t on_screen_ns;
    };
    Size size_;
    drivers::Clock& clock_;
    std::int64_t latency_ns_;
    std::vector<Image<std::uint8_t>> patterns_;
    RecordLog<Scheduled> schedule_; // chronological
    std::optional<Scheduled> pending_;
    RecordLog<drivers::FlipEvent> flips_;
    std::uint64_t sequence_ = 0;
    bool restored_ = false;
    bool fail_next_flip_ = false;
    std::atomic<bool> connected_{true}; // set from a test's thread between scans
    bool lose_next_event_ = false;
    std::int64_t event_lead_ns_ = 0;
    std::function<void(const drivers::FlipEvent&)> hook_;
};

} // namespace fpp::sim
