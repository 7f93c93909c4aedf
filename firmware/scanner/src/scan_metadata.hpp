#pragma once
// scan.json (format fpp-scan/1): what a scan folder says about itself: board,
// camera and projector, sequence, table, decode methods and statistics
// (fpp/decode_report.hpp), points, timings and every flip with its frame.
// Format: firmware/core/formats/scan-json.md
#include "fpp/decode_report.hpp"
#include "fpp/scanner/board_config.hpp"
#include "fpp/scanner/scanner.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace fpp::scanner {

// One flip and its frame.
struct FrameRecord {
    drivers::FlipEvent flip;
    std::uint64_t frame_id = 0;
    std::int64_t frame_timestamp_ns = 0;
};

struct TableSummary {
    std::filesystem::path path;
    TableModel model = TableModel::ray;
    std::uint64_t file_hash = 0;
    std::uint64_t calibration_hash = 0;
    TableTrueness trueness; // the calibration's predicted trueness, if the table has it
};

struct ScanMetadata {
    const BoardConfig& board;
    const ScannerSettings& settings; // the exposure the scan ran at (without HDR)
    ScanMode mode = ScanMode::scan;
    std::string started_utc;
    Size camera;
    int camera_bit_depth = 8;
    Size projector;
    std::optional<TableSummary> table;
    std::string method_x;
    std::string method_y;
    const ScanOutcome& outcome;
    const std::vector<FrameRecord>& records;
    // Of the decode the cloud comes from: the single pass, or with HDR the
    // fused result (fused_decode_statistics); decode_statistics_of says which.
    const DecodeStatistics& decode_statistics;
    const char* decode_statistics_of; // "pass" or "fused"
};

std::string scan_json(const ScanMetadata& m);

// scan.json's `quality` (and the API's): good, coverage (decoded pixels over
// camera pixels), reasons, advice.
nlohmann::json quality_json(const ScanVerdict& verdict);

// "2026-11-26T14:31:25Z" of seconds since 1970 (how scan.json and the API
// write times).
std::string utc_text(std::int64_t unix_s);

// When `path` was last written, as utc_text; nullopt when it cannot be read.
std::optional<std::string> file_written_utc(const std::filesystem::path& path);

// Lower-case hex of a 64-bit hash, 16 digits (how scan.json and the API
// write table hashes).
std::string hex64(std::uint64_t v);

// A table's predicted trueness as scan.json and the API give it: null when
// the table has none, else the length, its depth, one sigma along depth
// and across (mm) and both in ppm of the length.
nlohmann::json trueness_json(const TableTrueness& t);

} // namespace fpp::scanner
