#pragma once
// The settings a person changes on a running scanner (through the API), kept
// in the file the board's `settings` key names so that they survive a
// restart:
//
//   format: fpp-scanner-settings/1
//   exposure_us: 8000          camera exposure, microseconds, 10..1000000
//
// Read strictly (InputError naming the file and field); written atomically.
#include <filesystem>
#include <optional>

namespace fpp::scanner {

inline constexpr double kMinExposureUs = 10.0;
inline constexpr double kMaxExposureUs = 1e6;

struct ScannerSettings {
    double exposure_us = 10000.0;
};

// nullopt when the file does not exist.
std::optional<ScannerSettings> read_settings_file(const std::filesystem::path& path);
void write_settings_file(const std::filesystem::path& path, const ScannerSettings& settings);

} // namespace fpp::scanner
