#pragma once
// A small persistent thread pool for row-parallel image loops.
//
// parallel_for(count, grain, fn) calls fn(begin, end, worker) on disjoint
// chunks of [0, count) and returns when all are done. The calling thread takes
// part (worker 0), so a pool of size 1 starts no thread at all. `worker` is in
// [0, size()) and stable for the duration of one call, so callers can keep one
// scratch buffer per worker. A parallel_for issued from inside a running chunk
// runs inline on that thread (no deadlock, no extra parallelism).

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

namespace fpp {

class ThreadPool {
public:
    // threads = 0: one per hardware thread.
    explicit ThreadPool(int threads = 0);
    ~ThreadPool();
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    // Threads taking part in a parallel_for, the caller included.
    int size() const { return static_cast<int>(workers_.size()) + 1; }

    // fn(int begin, int end, int worker); chunks hold `grain` indices (the last
    // may hold fewer). An exception thrown by fn is rethrown here after every
    // chunk has finished; remaining chunks are skipped.
    template <class F> void parallel_for(int count, int grain, F&& fn) {
        using Fn = std::remove_reference_t<F>;
        run(count, grain, const_cast<void*>(static_cast<const void*>(&fn)),
            [](void* ctx, int b, int e, int w) { (*static_cast<Fn*>(ctx))(b, e, w); });
    }

    // Threads for `requested` (0 = hardware concurrency, at least 1).
    static int resolve_threads(int requested);

    // A process-wide pool of resolve_threads(threads) threads, started on first
    // use and kept until exit: short jobs (a decode takes milliseconds) then
    // pay no thread start-up. Callers on several threads share it; their jobs
    // run one after the other (each job uses every thread anyway).
    static ThreadPool& shared(int threads = 0);

private:
    using Invoke = void (*)(void*, int, int, int);
    void run(int count, int grain, void* ctx, Invoke invoke);
    void worker_loop(int worker);
    void work(int worker);

    std::vector<std::thread> workers_;
    std::mutex mutex_;
    std::condition_variable wake_;
    std::condition_variable done_;
    bool stop_ = false;
    unsigned long generation_ = 0;
    int busy_ = 0; // workers still inside the current job

    // The current job (valid while a run() is in progress).
    void* ctx_ = nullptr;
    Invoke invoke_ = nullptr;
    int count_ = 0;
    int grain_ = 1;
    std::atomic<int> next_{0}; // next unclaimed index
    std::exception_ptr error_;
    std::mutex run_mutex_; // one job at a time per pool
};

} // namespace fpp
