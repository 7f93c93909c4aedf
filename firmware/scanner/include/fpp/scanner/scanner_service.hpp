#pragma once
// The scanner as a network device: one scan at a time, started by the button
// or by the API, and the work the API asks of the devices (a preview, a new
// exposure, a new table) done on the scanning thread between scans. Other
// threads (HTTP connections) only queue work and read the state.
//
// State: idle, scanning, or error (the last scan failed; the next good one
// clears it). Every change and a scan's progress go to ServiceEvents; what
// it reports are types (service_reports.hpp), which the API renders.
#include <atomic>
#include <chrono>
#include <deque>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <string>

#include <fpp/scanner/board_config.hpp>
#include <fpp/scanner/log.hpp>
#include <fpp/scanner/scanner.hpp>
#include <fpp/scanner/service_reports.hpp>

namespace fpp::scanner {

struct ServiceOptions {
    std::optional<std::filesystem::path> table_path;    // where uploaded tables go
    std::optional<std::filesystem::path> settings_file; // where exposure changes go
    std::string session_board_yaml;                     // a simulated session board's own
    bool simulated = false;
};

struct Preview {
    std::string png;
    double saturated = 0; // fraction of pixels at the top of the range
    double mean = 0;      // mean level, 0..1
};

class ScannerService final : public ScanObserver {
public:
    // `board` is the scanner's, as parsed; the settings a person changes
    // are the scanner's (Scanner::settings) and the settings file's.
    ScannerService(const BoardConfig& board, Scanner& scanner, Devices devices,
                   ServiceEvents& events, const Logger& log, ServiceOptions options);
    ~ScannerService() override;

    // On the scanning thread: button presses (scans in `button_mode`) and
    // queued work until `stop` (which also aborts a scan in progress).
    void run(ScanMode button_mode, const std::atomic<bool>& stop);

    // --- Any thread. Refusals throw ApiError (409 busy, 400 bad value, ...).
    // Starts a scan (into `session`'s folder when not empty): its id.
    std::string start_scan(ScanMode mode, const std::string& session = {});
    Preview preview();
    // Captures the projector response ramp into `session`'s folder as
    // response/ (replacing an earlier one).
    ResponseRecorded record_response(const std::string& session);
    double exposure_us() const;
    double set_exposure_us(double exposure_us);
    // Checks the uploaded file, installs it at the table path (the previous
    // one kept as PATH.previous) and uses it from the next scan on.
    TableDescription install_table(const std::filesystem::path& uploaded);

    ScannerStatus status() const;
    StateNow state() const;
    std::optional<TableDescription> table() const; // nullopt without a table
    std::optional<std::filesystem::path> table_path() const { return options_.table_path; }
    const std::filesystem::path& store() const { return board_.store.directory; }
    std::filesystem::path sessions_dir() const { return board_.store.directory / "sessions"; }
    const std::string& session_board_yaml() const { return options_.session_board_yaml; }

    // ScanObserver (the scanning thread).
    void scan_started(const std::string& id, ScanMode mode, int frames) override;
    void frame_captured(int frame, int frames) override;
    void decoded() override;
    void written(const ScanOutcome& outcome) override;
    void failed(const std::string& reason) override;

private:
    struct Job;
    void serve_once(ScanMode button_mode, const std::atomic<bool>& stop);
    void run_scan(ScanMode mode, const std::filesystem::path& folder, const std::string& source,
                  const std::string& session, const std::atomic<bool>& stop);
    void shut_down();                                                    // queued work is refused
    std::filesystem::path claim_scan_folder(const std::string& session); // under mutex_
    // Queues `work` for the scanning thread and waits for it (ApiError 409
    // while a scan is queued or running, 503 when it does not run in 30 s).
    void run_on_scanner_thread(std::function<void()> work);
    bool set_state(ScannerState state, const std::string& error); // true if it changed
    // On the scanning thread: the idle wait for a press (50 ms), true on
    // one. A button whose line failed (DeviceError: its GPIO chip went away)
    // puts the scanner in the error state with the reason, and is asked
    // again once a second; when it answers the error ends.
    bool wait_for_button();
    void button_lost(const std::string& why);
    void button_back();
    void drop_presses_during_scan(); // on the scanning thread
    bool change_state_locked(ScannerState state, const std::string& error); // under mutex_
    void refresh_table();              // after the table changed
    std::uint64_t store_bytes() const; // under mutex_

    const BoardConfig& board_;
    Scanner& scanner_;
    Devices dev_;
    ServiceEvents& events_;
    const Logger& log_;
    ServiceOptions options_;
    const Size camera_size_;
    const int camera_bit_depth_;
    const Size projector_size_;

    mutable std::mutex mutex_;
    std::deque<std::shared_ptr<Job>> jobs_;
    bool busy_ = false; // a scan accepted or running
    bool stopping_ = false;
    ScannerState state_ = ScannerState::idle;
    std::string error_;
    std::optional<ScanEnd> last_scan_;
    std::optional<TableDescription> table_;
    std::uint64_t table_hash_shown_ = 0; // the table table_ describes
    int scans_completed_ = 0;
    ScannerSettings settings_; // the scanner's, readable from any thread
    mutable std::uint64_t store_bytes_ = 0;
    mutable std::chrono::steady_clock::time_point store_bytes_at_{};
    // The scan running now (the scanning thread's own).
    std::string current_id_;
    std::string current_source_;
    std::string current_session_;
    ScanMode current_mode_ = ScanMode::scan;
    // The button's failure while it lasts, and when to ask again.
    std::optional<std::string> button_error_;
    std::chrono::steady_clock::time_point button_retry_at_{};
};

} // namespace fpp::scanner
