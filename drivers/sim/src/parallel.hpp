#pragma once
// Splits rows [0, rows) into contiguous bands, one per worker thread
// (internal). With threads <= 1 everything runs on the calling thread.

#include <algorithm>
#include <exception>
#include <thread>
#include <vector>

namespace fpp::sim::detail {

inline int resolve_threads(int requested) {
    if (requested > 0)
        return requested;
    const unsigned hw = std::thread::hardware_concurrency();
    return static_cast<int>(std::clamp(hw, 1u, 16u));
}

// fn(first_row, end_row) on each band; exceptions are rethrown on the caller.
template <class Fn> void parallel_rows(int rows, int threads, const Fn& fn) {
    const int n = std::max(1, std::min(threads, rows / 8));
    if (n <= 1) {
        fn(0, rows);
        return;
    }
    std::vector<std::thread> workers;
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(n));
    workers.reserve(static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) {
        const int y0 = static_cast<int>(static_cast<long long>(rows) * k / n);
        const int y1 = static_cast<int>(static_cast<long long>(rows) * (k + 1) / n);
        workers.emplace_back([&, k, y0, y1] {
            try {
                fn(y0, y1);
            } catch (...) {
                errors[static_cast<std::size_t>(k)] = std::current_exception();
            }
        });
    }
    for (auto& w : workers)
        w.join();
    for (auto& e : errors)
        if (e)
            std::rethrow_exception(e);
}

} // namespace fpp::sim::detail
