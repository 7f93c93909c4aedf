#pragma once
// What the scanner service reports, as types: its state, its status, the
// installed table, a scan's start and end, a recorded response ramp, and the
// events it sends while it works (ServiceEvents). The service knows no JSON:
// the API renders these (api_json.hpp, firmware/scanner/http-api.md).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <fpp/coefficient_table.hpp>
#include <fpp/enum_names.hpp>
#include <fpp/scanner/scan_verdict.hpp>
#include <fpp/scanner/scanner.hpp>
#include <fpp/scanner/settings_file.hpp>

namespace fpp::scanner {

// What the scanner is doing: waiting, scanning, or in error (a failed scan,
// a camera that does not answer, a button whose GPIO chip went away; the
// error's reason beside it).
enum class ScannerState { idle, scanning, error };
inline constexpr EnumName<ScannerState> kScannerStateNames[] = {
    {ScannerState::idle, "idle"},
    {ScannerState::scanning, "scanning"},
    {ScannerState::error, "error"},
};
const char* to_string(ScannerState state); // "idle", "scanning", "error"

struct StateNow {
    ScannerState state = ScannerState::idle;
    std::string error; // "" unless state is error
};

// The installed table: its file and what its header says.
struct TableDescription {
    std::filesystem::path path;
    TableInfo info;
    std::uint64_t bytes = 0;
    std::uint64_t file_hash = 0;              // FNV-1a 64 of the file
    std::optional<std::string> installed_utc; // when the file was written
};

struct ScanStart {
    std::string id;
    ScanMode mode = ScanMode::scan;
    int frames = 0;
    std::string source;  // "button" or "api"
    std::string session; // "" for the store's own scans
};

// How a scan ended: written (with its judgement) or failed (with the reason).
struct ScanEnd {
    std::string id;
    ScanMode mode = ScanMode::scan;
    bool ok = false;
    std::size_t points = 0;
    ScanVerdict quality; // of a written scan
    std::string error;   // of a failed one
    std::string session; // "" for the store's own scans
};

struct ResponseRecorded {
    std::vector<int> levels; // drive levels of the ramp, one frame each
    std::size_t frames = 0;
};

struct ScannerStatus {
    StateNow state;
    std::string board_name;
    bool simulated = false;
    bool session_board = false; // a simulated session board's own yaml is offered
    Size camera;
    int camera_bit_depth = 8;
    std::string pixel_format;
    ScannerSettings settings;
    Size display;
    std::string sequence_name;
    int sequence_frames = 0;
    std::optional<TableDescription> table;
    std::filesystem::path store_directory;
    std::uint64_t store_used_bytes = 0;
    std::uint64_t store_max_bytes = 0;
    std::size_t store_scans = 0;
    std::size_t store_sessions = 0;
    std::optional<ScanEnd> last_scan;
    int scans_completed = 0; // since the daemon started
};

// The service's events, in the order they happen. Called on the scanning
// thread (settings_changed and table_changed also on a request's thread once
// its work is done); implementations must return quickly.
class ServiceEvents {
public:
    virtual ~ServiceEvents() = default;
    virtual void state_changed(const StateNow& state) = 0;
    virtual void table_changed(const std::optional<TableDescription>& table) = 0;
    virtual void scan_started(const ScanStart& scan) = 0;
    virtual void frame_captured(const std::string& id, int frame, int frames) = 0;
    virtual void decoded(const std::string& id) = 0;
    virtual void scan_ended(const ScanEnd& scan) = 0;
    virtual void settings_changed(const ScannerSettings& settings) = 0;
};

} // namespace fpp::scanner
