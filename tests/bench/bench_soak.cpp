// The soak: 10,000 scans on one scanner process (the network daemon's parts
// on a tiny virtual scanner, tests/support/scanner_soak.hpp), the sim
// board's button and the HTTP API taking turns, the store pruned to 1 MiB.
// One iteration; the figures are counters. The bounds: no failure,
// resident memory and open descriptors of the last 1,000 scans within 1 % of
// the first 1,000 after a 200-scan warm-up, the store within its limit with
// no stray files. A short form runs in CI (ScannerSoak.*).
//
//   build/ci/tests/bench/bench_soak [--benchmark_counters_tabular=true]
//   FPP_SOAK_SCANS=2000 build/ci/tests/bench/bench_soak   (a shorter run)
#include <benchmark/benchmark.h>

#include "scanner_soak.hpp"

#include <cstdio>
#include <cstdlib>

namespace {

void BM_Soak(benchmark::State& state) {
    fpp::test::SoakOptions o;
    if (const char* scans = std::getenv("FPP_SOAK_SCANS"))
        o.scans = std::atoi(scans);
    o.window = std::min(1000, o.scans / 4);
    o.warmup = std::min(200, o.scans / 10);
    fpp::test::SoakFigures f;
    for (auto _ : state) {
        fpp::test::TempDir dir;
        f = fpp::test::run_soak(o, dir.path());
    }
    state.counters["scans"] = f.scans;
    state.counters["failures"] = f.failures;
    state.counters["ms_per_scan"] = 1e3 * f.seconds / f.scans;
    state.counters["rss_first_kib"] = f.rss_first_kib;
    state.counters["rss_last_kib"] = f.rss_last_kib;
    state.counters["rss_change_pct"] = 100.0 * f.rss_change();
    state.counters["fds_first"] = f.fds_first;
    state.counters["fds_last"] = f.fds_last;
    state.counters["store_scans"] = double(f.store_scans);
    state.counters["store_bytes"] = double(f.store_bytes);
    state.counters["store_limit"] = double(f.store_limit);
    state.counters["stray"] = double(f.stray.size());
    const bool ok = f.failures == 0 && std::abs(f.rss_change()) < 0.01 &&
                    std::abs(f.fds_change()) < 0.01 && f.store_bytes <= f.store_limit &&
                    f.stray.empty();
    std::printf("soak: %d scans (%d button, %d API), %d failed%s%s; RSS %.0f -> %.0f KiB "
                "(%+.2f %%); fds %.2f -> %.2f; store %zu scans, %llu of %llu bytes, %zu stray: "
                "%s\n",
                f.scans, f.button_scans, f.api_scans, f.failures,
                f.first_failure.empty() ? "" : ", first: ", f.first_failure.c_str(),
                f.rss_first_kib, f.rss_last_kib, 100.0 * f.rss_change(), f.fds_first, f.fds_last,
                f.store_scans, static_cast<unsigned long long>(f.store_bytes),
                static_cast<unsigned long long>(f.store_limit), f.stray.size(),
                ok ? "within the bounds" : "OUT OF BOUNDS");
    if (!ok)
        state.SkipWithError("the soak is out of its bounds (see the line above)");
}

} // namespace

BENCHMARK(BM_Soak)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_MAIN();
