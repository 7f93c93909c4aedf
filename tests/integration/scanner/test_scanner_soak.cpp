// The soak's short form (the 10,000-scan run is tests/bench/bench_soak.cpp):
// 600 scans, the sim board's button and the HTTP API taking turns on one
// scanner process, its store pruned to 1 MiB. Every scan must succeed,
// resident memory and open descriptors stay flat (the last 200 scans
// against the 200 after a 100-scan warm-up; not judged under AddressSanitizer),
// and the store holds only complete scans within its limit.
#include <gtest/gtest.h>

#include "scanner_soak.hpp"

#include <cstdio>

TEST(ScannerSoak, ButtonAndApiTakingTurnsShortForm) {
    fpp::test::TempDir dir;
    fpp::test::SoakOptions o;
    o.scans = 600;
    o.warmup = 100;
    o.window = 200;
    const fpp::test::SoakFigures f = fpp::test::run_soak(o, dir.path());
    std::printf("%d scans (%d button, %d API) in %.1f s, %d failed; RSS %.0f -> %.0f KiB "
                "(%+.2f %%), fds %.2f -> %.2f; store %zu scans, %llu of %llu bytes\n",
                f.scans, f.button_scans, f.api_scans, f.seconds, f.failures, f.rss_first_kib,
                f.rss_last_kib, 100.0 * f.rss_change(), f.fds_first, f.fds_last, f.store_scans,
                static_cast<unsigned long long>(f.store_bytes),
                static_cast<unsigned long long>(f.store_limit));
    EXPECT_EQ(f.scans, o.scans);
    EXPECT_EQ(f.failures, 0) << f.first_failure;
    EXPECT_EQ(f.button_scans, o.scans / 2);
    EXPECT_EQ(f.api_scans, o.scans / 2);
    // The bound: within 1 % (a leak of 1 KiB a scan is 200 KiB over
    // the 200 scans between the windows' centres, above 1 % of ~20 MiB).
#if !defined(__SANITIZE_ADDRESS__) // its quarantine and shadow memory grow with the heap's churn
    EXPECT_LT(std::abs(f.rss_change()), 0.01);
#endif
    EXPECT_LT(std::abs(f.fds_last - f.fds_first), 0.5);
    EXPECT_LE(f.store_bytes, f.store_limit);
    EXPECT_GT(f.store_scans, 0u);
    EXPECT_TRUE(f.stray.empty()) << f.stray.front();
}
