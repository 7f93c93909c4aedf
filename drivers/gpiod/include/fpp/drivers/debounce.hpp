#pragma once
// Debouncing of a push button seen as edge events (pure logic, no hardware).
//
// A press counts only when the line was quiet (no edge of either kind) for the
// whole window before it: contact bounce after a press, and the chatter of a
// release that looks like new presses, both follow another edge closely and
// are dropped. Timestamps are the kernel's event times, in ns.
#include <chrono>
#include <cstdint>

namespace fpp::drivers {

class Debouncer {
public:
    explicit Debouncer(std::chrono::nanoseconds window) : window_ns_(window.count()) {}

    // Feeds one edge in time order; true when it is a press that counts.
    bool edge(std::int64_t timestamp_ns, bool press) {
        const bool quiet = !seen_edge_ || timestamp_ns - last_edge_ns_ >= window_ns_;
        seen_edge_ = true;
        last_edge_ns_ = timestamp_ns;
        return press && quiet;
    }
    void reset() { seen_edge_ = false; }

private:
    std::int64_t window_ns_;
    bool seen_edge_ = false;
    std::int64_t last_edge_ns_ = 0;
};

} // namespace fpp::drivers
