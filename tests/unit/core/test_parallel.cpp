// The row-parallel thread pool: coverage of the index range, worker ids,
// errors, nested calls, and the process-wide pools shared by several callers
// (decodes running at the same time on different threads).

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <thread>
#include <vector>

namespace {

using fpp::ThreadPool;

// Every index in [0, count) is visited exactly once, in chunks of `grain`,
// by workers in [0, size()).
void expect_covers(ThreadPool& pool, int count, int grain) {
    std::vector<std::atomic<int>> visits(static_cast<std::size_t>(count));
    std::atomic<bool> bad_chunk{false}, bad_worker{false};
    pool.parallel_for(count, grain, [&](int b, int e, int worker) {
        if (b % grain != 0 || e - b > grain || e <= b)
            bad_chunk = true;
        if (worker < 0 || worker >= pool.size())
            bad_worker = true;
        for (int i = b; i < e; ++i)
            ++visits[static_cast<std::size_t>(i)];
    });
    EXPECT_FALSE(bad_chunk);
    EXPECT_FALSE(bad_worker);
    for (int i = 0; i < count; ++i)
        ASSERT_EQ(visits[static_cast<std::size_t>(i)], 1) << i;
}

TEST(ThreadPool, CoversTheRangeOnce) {
    for (int threads : {1, 2, 3}) {
        ThreadPool pool(threads);
        EXPECT_EQ(pool.size(), threads);
        expect_covers(pool, 1000, 7);
        expect_covers(pool, 5, 10);
        expect_covers(pool, 1, 1);
        pool.parallel_for(0, 4, [](int, int, int) { FAIL() << "called for an empty range"; });
    }
}

TEST(ThreadPool, RethrowsAndStaysUsable) {
    ThreadPool pool(3);
    EXPECT_THROW(pool.parallel_for(100, 1,
                                   [](int b, int, int) {
                                       if (b == 42)
                                           throw std::runtime_error("chunk 42");
                                   }),
                 std::runtime_error);
    expect_covers(pool, 300, 4);
}

TEST(ThreadPool, NestedCallsRunInline) {
    ThreadPool pool(2);
    std::atomic<int> inner{0};
    std::atomic<bool> other_worker{false};
    pool.parallel_for(8, 1, [&](int, int, int worker) {
        pool.parallel_for(10, 3, [&](int b, int e, int w) {
            if (w != worker)
                other_worker = true;
            inner += e - b;
        });
    });
    EXPECT_EQ(inner, 80);
    EXPECT_FALSE(other_worker);
}

TEST(ThreadPool, SharedPoolsAreKeyedByThreadCount) {
    EXPECT_EQ(&ThreadPool::shared(2), &ThreadPool::shared(2));
    EXPECT_NE(&ThreadPool::shared(2), &ThreadPool::shared(3));
    EXPECT_EQ(ThreadPool::shared(3).size(), 3);
    EXPECT_EQ(&ThreadPool::shared(0), &ThreadPool::shared(ThreadPool::resolve_threads(0)));
}

TEST(ThreadPool, SharedPoolServesSeveralCallersAtOnce) {
    ThreadPool& pool = ThreadPool::shared(2);
    std::vector<std::thread> callers;
    std::atomic<int> failures{0};
    for (int t = 0; t < 4; ++t)
        callers.emplace_back([&, t] {
            for (int round = 0; round < 50; ++round) {
                const int count = 97 + t;
                std::vector<int> seen(static_cast<std::size_t>(count), 0);
                pool.parallel_for(count, 5, [&](int b, int e, int) {
                    for (int i = b; i < e; ++i)
                        ++seen[static_cast<std::size_t>(i)];
                });
                for (int v : seen)
                    failures += v != 1;
            }
        });
    for (auto& c : callers)
        c.join();
    EXPECT_EQ(failures, 0);
}

// Decodes on several threads at once share one pool and give the bytes of a
// decode run alone.
TEST(ThreadPool, ConcurrentDecodesMatchASingleDecode) {
    const fpp::Size camera{160, 90};
    const fpp::Size projector{200, 100};
    fpp::PhaseBlock block;
    block.axis = fpp::Axis::x;
    block.period = 200;
    block.steps = 4;
    fpp::CaptureSet set;
    set.manifest.camera = camera;
    set.manifest.projector = projector;
    set.manifest.sequence = {block};
    for (int k = 0; k < block.steps; ++k) {
        fpp::Frame f;
        f.bit_depth = 8;
        f.u8 = fpp::Image<std::uint8_t>(camera);
        for (int y = 0; y < camera.height; ++y)
            for (int x = 0; x < camera.width; ++x) {
                const double p = 1.2 * x + 0.1 * y;
                const double phase = 2 * std::numbers::pi * (p / block.period + k / 4.0);
                f.u8.at(x, y) = static_cast<std::uint8_t>(std::lround(120 + 90 * std::cos(phase)));
            }
        set.frames.push_back(std::move(f));
    }
    fpp::DecodeOptions options;
    options.threads = 2;
    const fpp::DecodeResult alone = fpp::decode(set, options);
    ASSERT_EQ(alone.method_x, "direct");
    std::vector<fpp::DecodeResult> results(4);
    std::vector<std::thread> callers;
    for (std::size_t t = 0; t < results.size(); ++t)
        callers.emplace_back([&, t] {
            for (int round = 0; round < 10; ++round)
                results[t] = fpp::decode(set, options);
        });
    for (auto& c : callers)
        c.join();
    const std::size_t bytes = camera.area() * sizeof(float);
    for (const auto& r : results) {
        ASSERT_EQ(r.proj_x.size(), camera);
        EXPECT_EQ(std::memcmp(r.proj_x.data(), alone.proj_x.data(), bytes), 0);
        EXPECT_EQ(std::memcmp(r.mask.data(), alone.mask.data(), camera.area()), 0);
    }
}

} // namespace
