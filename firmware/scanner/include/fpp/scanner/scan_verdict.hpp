#pragma once
// Whether a written scan is worth keeping, judged from its decode statistics
// (fpp/decode_report.hpp), its points and the newest good scan in the store:
// a scan is always written, and a poor one is flagged with its reasons and
// one suggestion in plain words (scan.json's `quality`, the API, the page).
#include "fpp/decode_report.hpp"

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace fpp::scanner {

struct ScanVerdict {
    bool good = true;
    double coverage = 0; // decoded pixels / camera pixels
    std::vector<std::string> reasons;
    std::string advice; // one suggestion ("" when good)
};

// The newest scan in the store judged good, for comparison.
struct GoodScan {
    std::string id;
    double coverage = 0;
};

struct ScanEvidence {
    const DecodeStatistics& decode;
    std::size_t points = 0;
    bool expects_points = true;        // scan mode (capture mode makes no cloud)
    double exposure_us = 0;            // the longest exposure of the scan
    std::optional<GoodScan> last_good; // none for a scan outside the store
};

// Poor when: at least 20 % of the lit pixels saturated (lower the exposure);
// under 2 % of the camera lit, or at least half the lit pixels without
// fringe contrast (raise it); no point from a scan; under half the last good
// scan's share of decoded pixels (the part moved, or the exposure).
ScanVerdict judge_scan(const ScanEvidence& evidence);

// The newest of the store's scans (`list_scans` order) whose scan.json says
// it was good, skipping `except`; at most `look_back` scans read.
std::optional<GoodScan> newest_good_scan(const std::filesystem::path& store,
                                         const std::filesystem::path& except, int look_back = 50);

} // namespace fpp::scanner
