// A written scan judged from its decode statistics, points and the store's
// newest good scan (fpp/scanner/scan_verdict.hpp): each rule on its own, at
// its threshold, and the store read back.
#include <gtest/gtest.h>

#include "fpp/atomic_file.hpp"
#include "fpp/scanner/scan_verdict.hpp"
#include "test_support.hpp"

#include <filesystem>
#include <string>

namespace fs = std::filesystem;
using fpp::DecodeStatistics;
using fpp::scanner::GoodScan;
using fpp::scanner::judge_scan;
using fpp::scanner::ScanVerdict;

namespace {

// 1000 camera pixels, `lit` of them lit, `decoded` of those decoded, the
// rest of the lit ones split as given.
DecodeStatistics counts(std::size_t lit, std::size_t decoded, std::size_t saturated = 0,
                        std::size_t low_modulation = 0) {
    DecodeStatistics d;
    d.pixels = 1000;
    d.lit = lit;
    d.decoded = decoded;
    d.saturated = saturated;
    d.low_modulation = low_modulation;
    d.dark = 1000 - lit;
    d.other = lit - decoded - saturated - low_modulation;
    return d;
}

ScanVerdict judge(const DecodeStatistics& d, std::size_t points = 500,
                  std::optional<GoodScan> last = std::nullopt, bool scan_mode = true) {
    return judge_scan({d, points, scan_mode, 8000, std::move(last)});
}

bool mentions(const ScanVerdict& v, const std::string& text) {
    for (const auto& r : v.reasons)
        if (r.find(text) != std::string::npos)
            return true;
    return false;
}

} // namespace

TEST(ScanVerdict, AGoodScanHasNoReasonAndNoAdvice) {
    const ScanVerdict v = judge(counts(600, 560, 100, 0), 560, GoodScan{"scan-a", 1.0});
    EXPECT_TRUE(v.good);
    EXPECT_DOUBLE_EQ(v.coverage, 0.56);
    EXPECT_TRUE(v.reasons.empty());
    EXPECT_EQ(v.advice, "");
}

TEST(ScanVerdict, SaturationFromAFifthOfTheLitPixelsAsksForLessExposure) {
    EXPECT_TRUE(judge(counts(600, 480, 119)).good); // 19.8 %
    const ScanVerdict v = judge(counts(600, 480, 120));
    EXPECT_FALSE(v.good);
    EXPECT_TRUE(mentions(v, "20 % of the lit pixels are saturated")) << v.reasons.front();
    EXPECT_EQ(v.advice, "Lower the exposure (now 8 ms).");
}

TEST(ScanVerdict, TooFewLitPixelsOrTooLittleContrastAskForMoreExposure) {
    EXPECT_TRUE(judge(counts(20, 20)).good); // 2 % lit
    const ScanVerdict dark = judge(counts(19, 19));
    EXPECT_FALSE(dark.good);
    EXPECT_TRUE(mentions(dark, "only 1.9 % of the camera's pixels see the fringes"));
    EXPECT_EQ(dark.advice.rfind("Raise the exposure (now 8 ms)", 0), 0u) << dark.advice;
    EXPECT_TRUE(judge(counts(600, 301, 0, 299)).good);
    const ScanVerdict flat = judge(counts(600, 300, 0, 300));
    EXPECT_TRUE(mentions(flat, "50 % of the lit pixels show too little fringe contrast"));
    EXPECT_EQ(flat.advice, "Raise the exposure (now 8 ms).");
}

TEST(ScanVerdict, NoPointIsPoorInScanModeOnly) {
    const ScanVerdict none = judge(counts(600, 560), 0);
    EXPECT_FALSE(none.good);
    EXPECT_TRUE(mentions(none, "no point was made"));
    EXPECT_FALSE(none.advice.empty());
    EXPECT_TRUE(judge(counts(600, 560), 0, std::nullopt, false).good); // capture mode
}

TEST(ScanVerdict, HalfTheLastGoodScansCoverageOrLessIsPoor) {
    const GoodScan last{"scan-20261129-101010-000", 0.5};
    EXPECT_TRUE(judge(counts(600, 250), 250, last).good); // 25 % of 50 %: not below half
    const ScanVerdict v = judge(counts(600, 249), 249, last);
    EXPECT_FALSE(v.good);
    EXPECT_TRUE(mentions(v, "25 % of the camera decoded, against 50 % in the last good scan "
                            "(scan-20261129-101010-000)"))
        << v.reasons.front();
    EXPECT_EQ(v.advice, "Check that the part is in the field of view and in focus.");
}

TEST(ScanVerdict, TheNewestGoodScanIsReadFromTheStore) {
    fpp::test::TempDir store;
    auto write = [&](const std::string& id, const std::string& quality) {
        fs::create_directories(store / id);
        fpp::write_file_synced(store / id / "scan.json",
                               "{\"format\": \"fpp-scan/1\"" +
                                   (quality.empty() ? "" : ", \"quality\": " + quality) + "}\n");
    };
    write("scan-20261129-100000-000", R"({"good": true, "coverage": 0.61})");
    write("scan-20261129-100100-000", R"({"good": true, "coverage": 0.58})");
    write("scan-20261129-100200-000", R"({"good": false, "coverage": 0.02})");
    write("scan-20261129-100300-000", "");                      // an older scanner's: no quality
    fs::create_directories(store / "scan-20261129-100400-000"); // no scan.json
    const auto newest = fpp::scanner::newest_good_scan(store.path(), {});
    ASSERT_TRUE(newest);
    EXPECT_EQ(newest->id, "scan-20261129-100100-000");
    EXPECT_DOUBLE_EQ(newest->coverage, 0.58);
    const auto skipping =
        fpp::scanner::newest_good_scan(store.path(), store / "scan-20261129-100100-000");
    ASSERT_TRUE(skipping);
    EXPECT_EQ(skipping->id, "scan-20261129-100000-000");
    EXPECT_FALSE(fpp::scanner::newest_good_scan(store.path(), {}, 3));
    EXPECT_FALSE(fpp::scanner::newest_good_scan(store / "nothing-here", {}));
}
