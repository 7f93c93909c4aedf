#include "fpp/parallel.hpp"

#include <algorithm>
#include <map>
#include <memory>

namespace fpp {

namespace {
// The pool whose chunk this thread is executing, to run nested calls inline.
thread_local const ThreadPool* t_running_pool = nullptr;
thread_local int t_worker = 0;
} // namespace

int ThreadPool::resolve_threads(int requested) {
    if (requested > 0)
        return requested;
    const unsigned hw = std::thread::hardware_concurrency();
    return hw == 0 ? 1 : static_cast<int>(hw);
}

ThreadPool& ThreadPool::shared(int threads) {
    static std::mutex mutex;
    static std::map<int, std::unique_ptr<ThreadPool>> pools; // by thread count
    const int n = resolve_threads(threads);
    std::lock_guard lock(mutex);
    std::unique_ptr<ThreadPool>& pool = pools[n];
    if (!pool)
        pool = std::make_unique<ThreadPool>(n);
    return *pool;
}

ThreadPool::ThreadPool(int threads) {
    const int n = resolve_threads(threads);
    workers_.reserve(static_cast<std::size_t>(n - 1));
    for (int w = 1; w < n; ++w)
        workers_.emplace_back([this, w] { worker_loop(w); });
}

ThreadPool::~ThreadPool() {
    {
        std::lock_guard lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    for (auto& t : workers_)
        t.join();
}

void ThreadPool::work(int worker) {
    const ThreadPool* outer = t_running_pool;
    const int outer_worker = t_worker;
    t_running_pool = this;
    t_worker = worker;
    for (;;) {
        const int begin = next_.fetch_add(grain_, std::memory_order_relaxed);
        if (begin >= count_)
            break;
        const int end = std::min(count_, begin + grain_);
        try {
            invoke_(ctx_, begin, end, worker);
        } catch (...) {
            std::lock_guard lock(mutex_);
            if (!error_)
                error_ = std::current_exception();
            next_.store(count_, std::memory_order_relaxed); // skip what is left
        }
    }
    t_running_pool = outer;
    t_worker = outer_worker;
}

void ThreadPool::worker_loop(int worker) {
    unsigned long seen = 0;
    for (;;) {
        {
            std::unique_lock lock(mutex_);
            wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
            if (stop_)
                return;
            seen = generation_;
        }
        work(worker);
        {
            std::lock_guard lock(mutex_);
            if (--busy_ == 0)
                done_.notify_one();
        }
    }
}

void ThreadPool::run(int count, int grain, void* ctx, Invoke invoke) {
    if (count <= 0)
        return;
    grain = std::max(1, grain);
    // Inline when there is nothing to share or when called from one of our chunks.
    if (workers_.empty() || count <= grain || t_running_pool == this) {
        const int worker = t_running_pool == this ? t_worker : 0;
        for (int b = 0; b < count; b += grain)
            invoke(ctx, b, std::min(count, b + grain), worker);
        return;
    }
    std::lock_guard run_lock(run_mutex_);
    {
        std::lock_guard lock(mutex_);
        ctx_ = ctx;
        invoke_ = invoke;
        count_ = count;
        grain_ = grain;
        next_.store(0, std::memory_order_relaxed);
        error_ = nullptr;
        busy_ = static_cast<int>(workers_.size());
        ++generation_;
    }
    wake_.notify_all();
    work(0);
    std::exception_ptr error;
    {
        std::unique_lock lock(mutex_);
        done_.wait(lock, [&] { return busy_ == 0; });
        error = error_;
        error_ = nullptr;
    }
    if (error)
        std::rethrow_exception(error);
}

} // namespace fpp
