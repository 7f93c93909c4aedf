#pragma once
// What a simulated device records for tests to check (exposures, flips,
// trigger pulses, LED states). Unlimited by default; a scanner that runs for
// months on the virtual board limits it (SimBoard::limit_records) and keeps
// the newest: past the limit the oldest half is dropped at once, so memory
// stays flat and a push costs O(1) amortised.
#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

namespace fpp::sim {

template <class T> class RecordLog {
public:
    static constexpr std::size_t kUnlimited = std::numeric_limits<std::size_t>::max();

    void push(const T& item) {
        if (items_.size() >= limit_) {
            const std::size_t drop = items_.size() - limit_ / 2;
            items_.erase(items_.begin(), items_.begin() + static_cast<std::ptrdiff_t>(drop));
            dropped_ += drop;
        }
        items_.push_back(item);
    }
    // The records kept, oldest first.
    const std::vector<T>& items() const { return items_; }
    // Every record pushed, dropped ones included.
    std::size_t total() const { return dropped_ + items_.size(); }
    bool empty() const { return items_.empty(); }
    const T& back() const { return items_.back(); }
    // At least 2 (half of it is kept when it is reached).
    void set_limit(std::size_t limit) { limit_ = std::max<std::size_t>(limit, 2); }

private:
    std::vector<T> items_;
    std::size_t dropped_ = 0;
    std::size_t limit_ = kUnlimited;
};

} // namespace fpp::sim
