#include "fpp/scanner/scanner_service.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/drivers/device_error.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/scanner/api_error.hpp"
#include "fpp/scanner/scan_store.hpp"
#include "fpp/scanner/settings_file.hpp"
#include "scan_metadata.hpp" // file_written_utc

#include <algorithm>
#include <cerrno>
#include <ctime>
#include <future>
#include <thread>
#include <unistd.h>

namespace fpp::scanner {

namespace fs = std::filesystem;

namespace {

void throw_if_aborted(const std::exception_ptr& e) {
    try {
        std::rethrow_exception(e);
    } catch (const ScanAborted&) {
        throw;
    } catch (...) {
    }
}

constexpr auto kJobTimeout = std::chrono::seconds(30);

// The largest value of a GenICam mono pixel format.
double top_of(const std::string& pixel_format) {
    for (const auto& [name, top] : {std::pair{"Mono10", 1023.0}, std::pair{"Mono12", 4095.0},
                                    std::pair{"Mono14", 16383.0}, std::pair{"Mono16", 65535.0}})
        if (pixel_format == name)
            return top;
    return 255.0;
}

// Mean level and saturated fraction of a frame (0..1 of the format's range).
void frame_levels(const Frame& f, double top, Preview& p) {
    const auto measure = [&](const auto& image) {
        double sum = 0;
        std::size_t saturated = 0;
        const std::size_t n = static_cast<std::size_t>(image.width()) * image.height();
        for (std::size_t i = 0; i < n; ++i) {
            const double v = image.data()[i];
            sum += v;
            saturated += v >= top ? 1 : 0;
        }
        p.mean = n ? sum / (static_cast<double>(n) * top) : 0;
        p.saturated = n ? static_cast<double>(saturated) / static_cast<double>(n) : 0;
    };
    if (f.bit_depth == 8)
        measure(f.u8);
    else
        measure(f.u16);
}

void fsync_directory(const fs::path& dir) {
    try {
        fsync_path(dir);
    } catch (const IoError&) {
        // The rename is done; a directory that cannot be synced only risks
        // the old name after a power cut.
    }
}

} // namespace

struct ScannerService::Job {
    std::function<void(const std::atomic<bool>&)> work;
    std::promise<void> done;
};

ScannerService::ScannerService(const BoardConfig& board, Scanner& scanner, Devices devices,
                               ServiceEvents& events, const Logger& log, ServiceOptions options)
    : board_(board), scanner_(scanner), dev_(devices), events_(events), log_(log),
      options_(std::move(options)), camera_size_(devices.camera.size()),
      camera_bit_depth_(devices.camera.bit_depth()), projector_size_(devices.display.size()),
      settings_(scanner.settings()) {
    scanner_.set_observer(this);
    refresh_table();
}

ScannerService::~ScannerService() {
    scanner_.set_observer(nullptr);
}

void ScannerService::refresh_table() {
    std::optional<TableDescription> t;
    if (scanner_.has_table()) {
        t.emplace();
        t->path = scanner_.table_path();
        t->info = scanner_.table().info();
        std::error_code ec;
        const auto bytes = fs::file_size(t->path, ec);
        t->bytes = ec ? 0 : bytes;
        t->file_hash = scanner_.table_file_hash();
        t->installed_utc = file_written_utc(t->path);
    }
    const std::lock_guard lock(mutex_);
    table_ = std::move(t);
    table_hash_shown_ = scanner_.table_file_hash();
}

// ---------------------------------------------------------------- scanning thread

void ScannerService::run(ScanMode button_mode, const std::atomic<bool>& stop) {
    dev_.led.set(drivers::LedState::ready);
    log_.info("idle: waiting for the button or a request");
    try {
        while (!stop.load())
            serve_once(button_mode, stop);
    } catch (const ScanAborted&) {
        // A stop request during a scan: logged by the scanner, nothing written.
    }
    shut_down();
}

// One queued piece of work, or one wait for the button (and its scan).
void ScannerService::serve_once(ScanMode button_mode, const std::atomic<bool>& stop) {
    std::shared_ptr<Job> job;
    {
        const std::lock_guard lock(mutex_);
        if (!jobs_.empty()) {
            job = jobs_.front();
            jobs_.pop_front();
        }
    }
    if (job) {
        try {
            job->work(stop);
            job->done.set_value();
        } catch (...) {
            job->done.set_exception(std::current_exception());
            throw_if_aborted(std::current_exception());
        }
        return;
    }
    if (!wait_for_button())
        return;
    fs::path folder;
    try {
        const std::lock_guard lock(mutex_);
        if (busy_) {
            log_.warning("button pressed while a scan is queued: ignored");
            return;
        }
        folder = claim_scan_folder({});
        busy_ = true;
    } catch (const std::exception& e) {
        log_.error(std::string("scan failed: ") + e.what());
        set_state(ScannerState::error, e.what());
        return;
    }
    run_scan(button_mode, folder, "button", {}, stop);
}

void ScannerService::shut_down() {
    std::deque<std::shared_ptr<Job>> left;
    {
        const std::lock_guard lock(mutex_);
        stopping_ = true;
        left.swap(jobs_);
    }
    for (auto& job : left)
        job->done.set_exception(std::make_exception_ptr(ApiError(503, "the scanner is stopping")));
}

void ScannerService::run_scan(ScanMode mode, const fs::path& folder, const std::string& source,
                              const std::string& session, const std::atomic<bool>& stop) {
    // Known before scan_started(): a scan that fails before it starts (its
    // table no longer loads) is reported with its own id.
    current_id_ = folder.filename().string();
    current_mode_ = mode;
    current_source_ = source;
    current_session_ = session;
    // busy_ ends in written() or failed(), before their events go out: a
    // request sent on `written` is taken. Clearing it here, after them,
    // refused such a request (409) and could end the busy_ of the next one.
    // Presses during the scan are dropped there too, for the same reason.
    try {
        scanner_.scan(mode, &stop, folder);
    } catch (const ScanAborted&) {
        throw;
    } catch (const std::exception&) {
        // Logged by the scanner and reported through failed().
    }
    log_.info("idle: waiting for the button or a request");
}

bool ScannerService::wait_for_button() {
    constexpr auto kIdleWait = std::chrono::milliseconds(50); // how soon queued work starts
    if (button_error_ && std::chrono::steady_clock::now() < button_retry_at_) {
        std::this_thread::sleep_for(kIdleWait);
        return false;
    }
    try {
        const bool pressed = dev_.button.wait_press(kIdleWait);
        if (button_error_)
            button_back();
        return pressed;
    } catch (const drivers::DeviceError& e) {
        button_lost(e.what());
        return false;
    }
}

void ScannerService::button_lost(const std::string& why) {
    // Looked for again once a second: opening a chip that is away is cheap,
    // but the log and the events say it once (and again if the reason
    // changes, e.g. the line came back held by another process).
    button_retry_at_ = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    const bool news = !button_error_ || *button_error_ != why;
    button_error_ = why;
    if (news)
        log_.error("button: " + why +
                   "; looked for again every second (scans through the API still run)");
    // Again after a scan that ended the error state: it is still true.
    if (set_state(ScannerState::error, why) || news) {
        try {
            dev_.led.set(drivers::LedState::error);
        } catch (const drivers::DeviceError&) {
        }
    }
}

void ScannerService::button_back() {
    const std::string was = *button_error_;
    button_error_.reset();
    log_.info("button answers again (was: " + was + ")");
    bool ended = false;
    {
        const std::lock_guard lock(mutex_);
        // Only the button's own error: a failed scan's stays until the next scan.
        if (state_ == ScannerState::error && error_ == was)
            ended = change_state_locked(ScannerState::idle, {});
    }
    if (ended) {
        events_.state_changed({ScannerState::idle, {}});
        dev_.led.set(drivers::LedState::ready);
    }
    log_.info("idle: waiting for the button or a request");
}

void ScannerService::drop_presses_during_scan() {
    // Before the scan is reported done: a press after `written` (or a status
    // that says idle) starts the next scan. Dropped after them, such a press
    // was lost (seen in the soak: 3 in 3,000 scans). A button that went away
    // has nothing queued; the idle wait reports it.
    int ignored = 0;
    try {
        ignored = dev_.button.drain();
    } catch (const drivers::DeviceError&) {
    }
    if (ignored > 0)
        log_.warning("button pressed " + std::to_string(ignored) +
                     " time(s) during the scan: ignored");
}

void ScannerService::scan_started(const std::string& id, ScanMode mode, int frames) {
    // The scan has just reloaded a table file that changed on disk
    // (Scanner::scan): described before anything of the scan is reported.
    if (scanner_.table_file_hash() != table_hash_shown_) {
        refresh_table();
        events_.table_changed(table());
    }
    current_id_ = id;
    current_mode_ = mode;
    set_state(ScannerState::scanning, {});
    events_.scan_started({id, mode, frames, current_source_, current_session_});
}

void ScannerService::frame_captured(int frame, int frames) {
    events_.frame_captured(current_id_, frame, frames);
}

void ScannerService::decoded() {
    events_.decoded(current_id_);
}

void ScannerService::written(const ScanOutcome& outcome) {
    drop_presses_during_scan();
    const ScanEnd end{current_id_, current_mode_,   true, outcome.points, outcome.verdict,
                      {},          current_session_};
    bool state_changed = false;
    {
        const std::lock_guard lock(mutex_);
        last_scan_ = end;
        ++scans_completed_;
        busy_ = false;
        store_bytes_at_ = {}; // measure again
        // The state changes with busy_, under one lock: a status read by a
        // client woken by `written` says idle. Its event follows `written`.
        state_changed = change_state_locked(ScannerState::idle, {});
    }
    events_.scan_ended(end);
    if (state_changed)
        events_.state_changed({ScannerState::idle, {}});
}

void ScannerService::failed(const std::string& reason) {
    drop_presses_during_scan();
    const ScanEnd end{current_id_, current_mode_, false, 0, {}, reason, current_session_};
    bool state_changed = false;
    {
        const std::lock_guard lock(mutex_);
        last_scan_ = end;
        busy_ = false;
        store_bytes_at_ = {};
        state_changed = change_state_locked(ScannerState::error, reason);
    }
    events_.scan_ended(end);
    if (state_changed)
        events_.state_changed({ScannerState::error, reason});
}

const char* to_string(ScannerState state) {
    return name_of(kScannerStateNames, state);
}

bool ScannerService::set_state(ScannerState state, const std::string& error) {
    bool changed = false;
    {
        const std::lock_guard lock(mutex_);
        changed = change_state_locked(state, error);
    }
    if (changed)
        events_.state_changed({state, error});
    return changed;
}

bool ScannerService::change_state_locked(ScannerState state, const std::string& error) {
    if (state_ == state && error_ == error)
        return false;
    state_ = state;
    error_ = error;
    return true;
}

// ---------------------------------------------------------------- any thread

fs::path ScannerService::claim_scan_folder(const std::string& session) {
    if (session.empty()) {
        prepare_store(board_.store.directory);
        return new_scan_folder(board_.store.directory);
    }
    const fs::path dir = sessions_dir() / session;
    if (!fs::is_directory(dir))
        throw ApiError(404, "no session '" + session + "'");
    return new_scan_folder(dir);
}

std::string ScannerService::start_scan(ScanMode mode, const std::string& session) {
    const std::lock_guard lock(mutex_);
    if (stopping_)
        throw ApiError(503, "the scanner is stopping");
    if (busy_)
        throw ApiError(409, "a scan is running: one at a time");
    if (mode == ScanMode::scan && !table_)
        throw ApiError(409, "no table is loaded: install one (PUT /api/v1/table) or scan in "
                            "capture mode");
    fs::path folder;
    try {
        folder = claim_scan_folder(session);
    } catch (const IoError& e) {
        throw ApiError(507, e.what());
    }
    busy_ = true;
    auto job = std::make_shared<Job>();
    job->work = [this, mode, folder, session](const std::atomic<bool>& stop) {
        run_scan(mode, folder, "api", session, stop);
    };
    jobs_.push_back(std::move(job));
    return folder.filename().string();
}

void ScannerService::run_on_scanner_thread(std::function<void()> work) {
    auto job = std::make_shared<Job>();
    job->work = [work = std::move(work)](const std::atomic<bool>&) { work(); };
    std::future<void> done = job->done.get_future();
    {
        const std::lock_guard lock(mutex_);
        if (stopping_)
            throw ApiError(503, "the scanner is stopping");
        if (busy_)
            throw ApiError(409, "a scan is running: try again when it has ended");
        jobs_.push_back(job);
    }
    if (done.wait_for(kJobTimeout) != std::future_status::ready)
        throw ApiError(503, "the scanner did not answer within 30 s");
    done.get();
}

Preview ScannerService::preview() {
    Frame frame;
    run_on_scanner_thread([&] {
        try {
            frame = scanner_.preview();
        } catch (const std::exception& e) {
            throw ApiError(503, std::string("preview failed: ") + e.what());
        }
    });
    Preview p;
    frame_levels(frame, frame.bit_depth == 8 ? 255.0 : top_of(board_.camera.settings.pixel_format),
                 p);
    p.png = encode_png(frame);
    return p;
}

ResponseRecorded ScannerService::record_response(const std::string& session) {
    const std::filesystem::path folder = sessions_dir() / session / "response";
    ResponseRecorded result;
    run_on_scanner_thread([&] {
        ResponseRamp ramp;
        try {
            ramp = scanner_.capture_ramp();
        } catch (const std::exception& e) {
            throw ApiError(503, std::string("response ramp failed: ") + e.what());
        }
        try {
            std::filesystem::remove_all(folder);
            write_response_ramp(folder, ramp);
        } catch (const std::exception& e) {
            throw ApiError(507, std::string("response ramp not written: ") + e.what());
        }
        result = {ramp.levels, ramp.frames.size()};
    });
    log_.info("http: projector response ramp recorded into session " + session);
    return result;
}

double ScannerService::exposure_us() const {
    const std::lock_guard lock(mutex_);
    return settings_.exposure_us;
}

double ScannerService::set_exposure_us(double exposure_us) {
    if (!(exposure_us >= kMinExposureUs && exposure_us <= kMaxExposureUs))
        throw ApiError(400, "exposure_us: must be in 10..1000000");
    if (!options_.settings_file)
        throw ApiError(409, "the board names no settings file (board key settings, or "
                            "--settings)");
    const ScannerSettings wanted{exposure_us};
    run_on_scanner_thread([&] {
        const ScannerSettings before = scanner_.settings();
        try {
            scanner_.apply_settings(wanted);
            write_settings_file(*options_.settings_file, wanted);
        } catch (const std::exception& e) {
            try {
                scanner_.apply_settings(before);
            } catch (const std::exception&) {
            }
            throw ApiError(503, std::string("exposure not changed: ") + e.what());
        }
    });
    {
        const std::lock_guard lock(mutex_);
        settings_ = wanted;
    }
    log_.info("exposure set to " + std::to_string(exposure_us) + " us");
    events_.settings_changed(wanted);
    return exposure_us;
}

TableDescription ScannerService::install_table(const fs::path& uploaded) {
    if (!options_.table_path)
        throw ApiError(409, "the board names no table path (board key table, or --table)");
    const fs::path target = *options_.table_path;
    run_on_scanner_thread([&] {
        // The strict loader first: a bad table is refused and the one in use stays.
        try {
            scanner_.reload_table(uploaded);
        } catch (const InputError& e) {
            // The spool file's name means nothing to the client.
            std::string why = e.what();
            if (why.starts_with(uploaded.string()))
                why = "the uploaded table" + why.substr(uploaded.string().size());
            throw ApiError(400, why);
        }
        try {
            // The previous file kept by a second name, then the new one
            // renamed over the old: the path always holds a whole table.
            if (fs::exists(target)) {
                const fs::path previous = target.string() + ".previous";
                const fs::path link = target.string() + ".previous.tmp";
                fs::remove(link);
                fs::create_hard_link(target, link);
                fs::rename(link, previous);
            }
            fs::rename(uploaded, target);
            fsync_directory(target.parent_path());
            scanner_.reload_table(target);
        } catch (const std::exception& e) {
            if (fs::exists(target))
                scanner_.reload_table(target);
            throw ApiError(507, std::string("table not installed: ") + e.what());
        }
        refresh_table();
    });
    std::optional<TableDescription> installed = table();
    events_.table_changed(installed);
    return *installed;
}

std::optional<TableDescription> ScannerService::table() const {
    const std::lock_guard lock(mutex_);
    return table_;
}

std::uint64_t ScannerService::store_bytes() const {
    const auto now = std::chrono::steady_clock::now();
    if (now - store_bytes_at_ > std::chrono::seconds(1)) {
        store_bytes_ = folder_bytes(board_.store.directory);
        store_bytes_at_ = now;
    }
    return store_bytes_;
}

StateNow ScannerService::state() const {
    const std::lock_guard lock(mutex_);
    return {state_, error_};
}

ScannerStatus ScannerService::status() const {
    ScannerStatus st;
    st.store_scans = list_scans(board_.store.directory).size();
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(sessions_dir(), ec))
        st.store_sessions += e.is_directory() ? 1 : 0;
    st.board_name = board_.name;
    st.simulated = options_.simulated;
    st.session_board = !options_.session_board_yaml.empty();
    st.camera = camera_size_;
    st.camera_bit_depth = camera_bit_depth_;
    st.pixel_format = board_.camera.settings.pixel_format;
    st.display = projector_size_;
    st.sequence_name = board_.sequence_name.empty() ? "blocks" : board_.sequence_name;
    st.sequence_frames = scanner_.frames_per_scan();
    st.store_directory = board_.store.directory;
    st.store_max_bytes = board_.store.max_bytes;
    const std::lock_guard lock(mutex_);
    st.state = {state_, error_};
    st.settings = settings_;
    st.table = table_;
    st.store_used_bytes = store_bytes();
    st.last_scan = last_scan_;
    st.scans_completed = scans_completed_;
    return st;
}

} // namespace fpp::scanner
