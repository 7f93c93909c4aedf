#pragma once
// The board configuration file (format fpp-scanner-board/1): which devices
// the scanner drives and how (display, GPIO lines, camera, sequence, table,
// HDR, store, timing, HTTP API, simulator). Read strictly: unknown or
// duplicate keys, wrong types and out-of-range values throw
// InputError(file, field, message). Relative paths are relative to the board
// file's folder. A sim section makes a simulated board; without one the
// board is hardware (DRM display, GPIO lines, an Aravis camera).
// Format: firmware/core/formats/board-file.md (examples in board/*.yaml)
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <fpp/drivers/camera.hpp>
#include <fpp/enum_names.hpp>
#include <fpp/pattern_block.hpp>
#include <fpp/phase_noise.hpp>

namespace fpp::scanner {

inline constexpr const char* kBoardConfigFormat = "fpp-scanner-board/1";

struct DisplayConfig {
    std::string card = "auto";
    std::string connector = "auto";
    std::string mode = "auto"; // "auto" (preferred mode) or "WIDTHxHEIGHT"
};

struct GpioConfig {
    std::string chip = "gpiochip0";
    int trigger_line = 0;
    int button_line = 1;
    int led_line = 2;
    bool trigger_active_low = false;
    bool button_active_low = true;
    bool led_active_low = false;
    std::chrono::milliseconds debounce{30};
};

enum class CameraDriver { sim, aravis };
inline constexpr EnumName<CameraDriver> kCameraDriverNames[] = {{CameraDriver::sim, "sim"},
                                                                {CameraDriver::aravis, "aravis"}};

struct CameraConfig {
    CameraDriver driver = CameraDriver::sim;
    std::string device; // Aravis id or IP address; "" = first found
    drivers::CameraSettings settings;
    std::optional<CameraNoise> noise; // measured; without it points get no sigma_z
};

// High dynamic range: the sequence captured once per exposure and fused per
// pixel (fpp/exposure_fusion.hpp).
struct HdrConfig {
    std::vector<double> exposures_us; // fixed passes, in capture order; empty with automatic
    bool automatic = false;
    double max_saturated = 0.01;      // automatic: fraction of lit pixels the longest may saturate
    int passes = 3;                   // automatic: at most this many
    double ratio = 4;                 // automatic: each shorter exposure is this many times less
    std::optional<double> longest_us; // automatic: where the search starts
};

struct PointFilterConfig {
    std::optional<double> max_sigma_z_mm; // points with a larger predicted sigma_z are dropped
};

struct StoreConfig {
    std::filesystem::path directory;
    std::uint64_t max_bytes = 0; // oldest scans pruned beyond this (store.max_mb MiB)
};

struct TimingConfig {
    std::chrono::microseconds settle{0}; // after the flip event, before the trigger
    std::chrono::microseconds trigger_pulse{100};
    std::chrono::milliseconds flip_timeout{100};
};

// The HTTP API and page (firmware/scanner/http-api.md).
struct HttpConfig {
    std::string listen;               // "ADDRESS:PORT"; port 0 = any free port
    std::filesystem::path token_file; // the API's bearer token, first line
    int max_connections = 64;
    std::chrono::seconds timeout{30};              // an idle connection is closed after this
    std::optional<std::filesystem::path> web_root; // the page's files
};

struct ListenAddress {
    std::string host; // IPv4 or IPv6 literal
    int port = 0;
};

// "0.0.0.0:8080", "[::1]:8080" -> host and port; throws std::invalid_argument.
ListenAddress parse_listen_address(const std::string& text);

struct SimConfig {
    std::filesystem::path rig;
    std::string scene = "composite"; // named scene or resolved yaml path
    int binning = 1;
    std::chrono::microseconds flip_latency{16'667};
    bool virtual_clock = true;
    std::uint64_t seed = 1;
    bool camera_only = false; // display and lines are hardware
};

struct BoardConfig {
    std::filesystem::path file; // where it was read from
    std::string name;
    DisplayConfig display;
    GpioConfig gpio;
    CameraConfig camera;
    std::string sequence_name; // standard sequence, or "" when blocks are given
    Sequence sequence_blocks;  // when given as blocks
    std::optional<std::filesystem::path> table;
    std::optional<std::filesystem::path> projector_response;
    std::optional<HdrConfig> hdr;
    PointFilterConfig points;
    StoreConfig store;
    TimingConfig timing;
    std::optional<SimConfig> sim; // a simulated board (required with camera.driver sim)
    std::optional<HttpConfig> http;
    std::optional<std::filesystem::path> settings_file;

    // The sequence for a projector of this size (throws InputError naming
    // field "sequence" if it does not fit that projector).
    Sequence sequence(Size projector) const;
};

BoardConfig read_board_config(const std::filesystem::path& path);
BoardConfig parse_board_config(const std::string& yaml_text, const std::filesystem::path& origin);

} // namespace fpp::scanner
