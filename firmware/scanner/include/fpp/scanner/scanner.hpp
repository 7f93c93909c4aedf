#pragma once
// The scan: idle, button, then per pattern flip -> flip event -> settle ->
// trigger -> frame, each frame pushed to the streaming decoder while the next
// pattern flips; then finish, apply the table, write the outputs atomically
// into the scan store, prune it, back to idle.
//
// Written against the driver interfaces only: the same code runs on the
// virtual scanner and on hardware.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <fpp/coefficient_table.hpp>
#include <fpp/decoder.hpp>
#include <fpp/drivers/camera.hpp>
#include <fpp/drivers/clock.hpp>
#include <fpp/drivers/display.hpp>
#include <fpp/drivers/gpio.hpp>
#include <fpp/enum_names.hpp>
#include <fpp/exposure_fusion.hpp>
#include <fpp/patterns.hpp>
#include <fpp/phase_noise.hpp>
#include <fpp/point_cloud.hpp>
#include <fpp/projector_response.hpp>
#include <fpp/scanner/board_config.hpp>
#include <fpp/scanner/log.hpp>
#include <fpp/scanner/scan_verdict.hpp>
#include <fpp/scanner/settings_file.hpp>

namespace fpp::scanner {

struct Devices {
    drivers::Display& display;
    drivers::TriggerOutput& trigger;
    drivers::ButtonInput& button;
    drivers::StatusLed& led;
    drivers::Camera& camera;
    drivers::Clock& clock;
};

enum class ScanMode { scan, capture }; // capture also writes the raw capture set
// The API's and scan.json's names.
inline constexpr EnumName<ScanMode> kScanModeNames[] = {{ScanMode::scan, "scan"},
                                                        {ScanMode::capture, "capture"}};

// A scan stopped by a stop request (SIGTERM).
class ScanAborted : public std::runtime_error {
public:
    ScanAborted() : std::runtime_error("scan aborted") {}
};

// The frame did not show the pattern it was triggered for.
class PatternMismatch : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct ScanTimings {
    double capture_ms = 0;   // first show() to last frame received (scan clock)
    double push_mean_ms = 0; // streaming decoder work per frame (wall clock)
    double push_max_ms = 0;
    double finish_ms = 0; // last decode step (every pass's, HDR)
    double fuse_ms = 0;   // HDR: exposure fusion
    double apply_ms = 0;  // table kernel
    double write_ms = 0;  // outputs on disk (fsynced)
    double last_frame_to_written_ms = 0;
};

struct ScanOutcome {
    std::filesystem::path folder;
    std::size_t points = 0;
    int frames = 0;
    int attempts = 1;
    std::vector<double> exposures_us;  // one pass of the sequence per exposure, in capture order
    std::optional<FusionStats> fusion; // HDR scans
    bool has_sigma = false;            // points carry sigma_z (the board gives camera.noise)
    std::size_t dropped_by_sigma = 0;  // points over points.max_sigma_z_mm
    ScanVerdict verdict;               // good, or poor with its reasons (scan_verdict.hpp)
    ScanTimings timings;
};

// What a scan reports as it goes (the HTTP API's events). Called on the
// scanning thread; implementations must return quickly.
class ScanObserver {
public:
    virtual ~ScanObserver() = default;
    virtual void scan_started(const std::string& id, ScanMode mode, int frames) = 0;
    virtual void frame_captured(int frame, int frames) = 0; // frame counts from 1
    virtual void decoded() = 0;
    virtual void written(const ScanOutcome& outcome) = 0;
    virtual void failed(const std::string& reason) = 0;
};

class Scanner {
public:
    // Loads and checks the table (InputError naming the file: missing,
    // corrupt, or for another camera or projector) and the projector
    // response, checks the HDR exposures against the camera's range
    // (InputError naming hdr.exposures_us[i] and the range), renders the
    // patterns (through the response's inverse when there is one) and gives
    // them to the display. The devices must outlive the scanner.
    // The board stays as parsed: what a person changes while the scanner
    // runs (the exposure) is `settings`, the board's own when not given.
    Scanner(const BoardConfig& board, Devices devices, const Logger& log);
    Scanner(const BoardConfig& board, const ScannerSettings& settings, Devices devices,
            const Logger& log);

    // One scan: the sequence once, or once per exposure with hdr (fused per
    // pixel). A scan-mode scan first reloads the table when its file changed
    // on disk since it was loaded (another copied over it, or damaged): a
    // file that no longer loads fails the scan with its InputError, and every
    // scan after it, until the file is whole again or another is installed.
    // `stop`, when given and set, aborts between frames
    // (ScanAborted). A camera fault (DeviceError from the camera) fails the
    // attempt and the scan is tried once more. On failure the LED shows
    // error, nothing is left in the store, and the exception propagates.
    // `folder`: where the scan goes (a new folder in the board's store when
    // empty); the store is pruned only when it goes there.
    ScanOutcome scan(ScanMode mode, const std::atomic<bool>* stop = nullptr,
                     std::filesystem::path folder = {});

    // One frame with the projector all white (placing a board, setting the
    // exposure). Throws DeviceError.
    Frame preview();
    // The same at another exposure (the camera's own is restored after).
    Frame preview_at(double exposure_us);

    // The projector's response measured as calibration needs it: one frame
    // per uniform grey level of standard_ramp_levels() (fpp/projector_response.hpp),
    // drive levels as they are, not through the response's inverse. The
    // display holds the ramp's patterns meanwhile and the scan's again after.
    // Throws DeviceError.
    ResponseRamp capture_ramp();

    // Replaces the table used from the next scan on (loaded and checked as
    // in the constructor: InputError naming the file for a bad one, and the
    // table in use stays).
    void reload_table(const std::filesystem::path& path);

    void set_observer(ScanObserver* observer) { observer_ = observer; }

    const ScannerSettings& settings() const { return settings_; }
    // Sets the camera to `settings` and scans with them from the next scan
    // on. Throws DeviceError (the settings in use stay).
    void apply_settings(const ScannerSettings& settings);

    // Frames of one pass of the sequence (an HDR scan takes one pass per exposure).
    int frames_per_scan() const { return static_cast<int>(patterns_); }
    // Frames a scan takes: one pass per fixed HDR exposure, at most hdr.passes
    // with automatic exposures (the previews not counted).
    int planned_frames() const {
        const int passes = !board_.hdr ? 1
                           : board_.hdr->automatic
                               ? board_.hdr->passes
                               : static_cast<int>(board_.hdr->exposures_us.size());
        return static_cast<int>(patterns_) * passes;
    }
    const Sequence& sequence() const { return sequence_; }
    bool has_table() const { return !table_.empty(); }
    const CoefficientTable& table() const { return table_; }
    std::uint64_t table_file_hash() const { return table_file_hash_; }
    const std::filesystem::path& table_path() const { return table_path_; }

private:
    struct Captured;
    ScanOutcome attempt(ScanMode mode, const std::atomic<bool>* stop,
                        const std::filesystem::path& folder);
    // The pass exposures of the next scan ({} without hdr: the camera's own).
    std::vector<double> scan_exposures();
    void capture_pass(int pass, int passes, ScanMode mode, const std::atomic<bool>* stop,
                      Captured& captured, ScanOutcome& outcome, double& push_total);
    // Waits out the settle time after `flip` of pattern `pattern`, triggers
    // the camera and takes the frame. A frame that no trigger asked for
    // (one waiting before the trigger, or a software-triggered one that
    // arrived before its trigger was sent) fails the attempt with a camera
    // DeviceError, which retries it; a line-triggered frame exposed before
    // the flip throws PatternMismatch.
    drivers::CapturedFrame trigger_and_take(const drivers::FlipEvent& flip, std::size_t pattern);
    // No frame may wait before a trigger, nor after the last frame (an extra
    // frame earlier shifts every later one by one, and leaves one behind);
    // `where()` names the moment in the camera DeviceError.
    template <class Where> void check_no_frame_waiting(Where&& where) const;
    // The decoded coordinate and its predicted sigma for the table: the one
    // pass, or the passes fused.
    DecodeResult& combine_passes(ScanOutcome& outcome);
    PhaseNoiseModel noise_model() const;
    // The sequence's patterns (through the response's inverse when the board
    // has one) and a white one after them, onto the display.
    void prepare_patterns();
    // Flip to prepared patterns first .. first + count - 1 in turn and take
    // a frame of each (the camera started and stopped around them).
    std::vector<Frame> grab_prepared(std::size_t first, std::size_t count);
    CoefficientTable load_checked_table(const std::filesystem::path& path) const;
    // The table file as stat() saw it (nullopt: not there).
    struct FileStamp {
        std::uint64_t device = 0, inode = 0;
        std::int64_t size = 0, mtime_ns = 0, ctime_ns = 0;
        bool operator==(const FileStamp&) const = default;
    };
    static std::optional<FileStamp> stamp_of(const std::filesystem::path& path);
    void reload_table_if_changed();
    // `last_good`: the store's newest good scan, to judge this one against.
    void write_outputs(const std::filesystem::path& temp, ScanMode mode, Captured& captured,
                       DecodeResult& decoded, ScanOutcome& outcome,
                       const std::optional<GoodScan>& last_good);

    const BoardConfig& board_;
    ScannerSettings settings_;
    Devices dev_;
    const Logger& log_;
    Sequence sequence_;
    std::optional<GammaLut> response_lut_;
    std::size_t patterns_ = 0; // the sequence's; the display also holds a white one after them
    ScanObserver* observer_ = nullptr;
    CoefficientTable table_;
    std::uint64_t table_file_hash_ = 0;
    std::filesystem::path table_path_;
    std::optional<FileStamp> table_stamp_; // of the file when table_ was loaded from it
    // Memory reused scan after scan: a fresh decoder, result or cloud costs
    // page faults on every scan (tens of ms at 1600x1200).
    std::optional<StreamingDecoder> decoder_;
    std::vector<ExposurePass> passes_; // one per exposure of the last scan
    DecodeResult fused_;               // HDR
    Image<float> sigma_;               // predicted coordinate sigma (projector px)
    PointCloud cloud_;
};

} // namespace fpp::scanner
