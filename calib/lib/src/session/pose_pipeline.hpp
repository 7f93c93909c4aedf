#pragma once
// Poses of a session processed several at a time (internal to the session
// procedures). Each pose's work (read its frames, decode, find the board,
// ...) is independent of the others', so the threads of a pool each take the
// next pose as they finish one; what follows a pose (progress lines, adding
// it to the result) runs in pose order, as in a sequential loop.

#include "fpp/parallel.hpp"

#include <exception>
#include <mutex>
#include <vector>

namespace fpp::calib::detail {

// Runs process(k, worker) for every pose k in [0, count) on the threads of
// `pool` (`worker` in [0, pool.size()) for per-thread scratch; nested
// parallel_for calls on `pool` run inline), and finish(k) in
// increasing k, each as soon as process(0..k) have returned, one at a time.
// When a call throws, the poses not yet begun are skipped, the earlier
// ones still finish, and the exception of the lowest pose is rethrown.
template <class Process, class Finish>
void for_each_pose(ThreadPool& pool, int count, Process&& process, Finish&& finish) {
    std::vector<char> processed(static_cast<std::size_t>(count), 0);
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(count));
    std::mutex mutex; // guards processed, errors, next_to_finish and every finish() call
    int next_to_finish = 0;
    bool failed = false;
    pool.parallel_for(count, 1, [&](int begin, int end, int worker) {
        for (int k = begin; k < end; ++k) {
            {
                std::lock_guard lock(mutex);
                if (failed)
                    return;
            }
            std::exception_ptr error;
            try {
                process(k, worker);
            } catch (...) {
                error = std::current_exception();
            }
            std::lock_guard lock(mutex);
            processed[static_cast<std::size_t>(k)] = 1;
            if (error) {
                errors[static_cast<std::size_t>(k)] = error;
                failed = true;
            }
            while (next_to_finish < count && processed[static_cast<std::size_t>(next_to_finish)] &&
                   !errors[static_cast<std::size_t>(next_to_finish)]) {
                try {
                    finish(next_to_finish);
                } catch (...) {
                    errors[static_cast<std::size_t>(next_to_finish)] = std::current_exception();
                    failed = true;
                    break;
                }
                ++next_to_finish;
            }
        }
    });
    for (const std::exception_ptr& e : errors)
        if (e)
            std::rethrow_exception(e);
}

} // namespace fpp::calib::detail
