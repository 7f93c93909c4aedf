#include "fpp/scanner/scanner.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/drivers/device_error.hpp"
#include "fpp/error.hpp"
#include "fpp/patterns.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/scanner/scan_store.hpp"
#include "scan_metadata.hpp"
#include "fpp/table_kernel.hpp"
#include "fpp/yaml_fields.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <memory>

namespace fpp::scanner {

namespace fs = std::filesystem;
using drivers::LedState;

namespace {

double wall_ms() {
    return std::chrono::duration<double, std::milli>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

std::uint64_t hash_file(const fs::path& path) {
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                         &std::fclose);
    if (!file)
        throw IoError(path, "cannot open for hashing");
    std::string bytes(static_cast<std::size_t>(fs::file_size(path)), '\0');
    if (std::fread(bytes.data(), 1, bytes.size(), file.get()) != bytes.size())
        throw IoError(path, "short read while hashing");
    return fnv1a64(bytes.data(), bytes.size());
}

} // namespace

struct Scanner::Captured {
    std::vector<FrameRecord> records;
    std::vector<Frame> frames; // capture mode only
    std::string started_utc;
};

Scanner::Scanner(const BoardConfig& board, Devices devices, const Logger& log)
    : board_(board), dev_(devices), log_(log) {
    const Size projector = dev_.display.size();
    sequence_ = board_.sequence(projector);
    if (board_.table)
        reload_table(*board_.table);
    auto patterns = render_sequence(sequence_, projector);
    patterns_ = patterns.size();
    patterns.emplace_back(projector, 1, std::uint8_t{255}); // white, for previews
    // Made now, so that a scan never starts on a sequence the decoder rejects.
    decoder_.emplace(sequence_, dev_.camera.size(), projector);
    dev_.display.prepare(patterns);
    log_.info("board " + board_.name + ": " + std::to_string(patterns_) + " patterns at " +
              std::to_string(projector.width) + "x" + std::to_string(projector.height) +
              ", camera " + std::to_string(dev_.camera.size().width) + "x" +
              std::to_string(dev_.camera.size().height));
}

CoefficientTable Scanner::load_checked_table(const fs::path& path) const {
    const Size camera = dev_.camera.size();
    const Size projector = dev_.display.size();
    CoefficientTable table = load_table(path, &camera);
    if (table.info().projector != projector)
        throw InputError(path, "projector_size",
                         "table made for a " + std::to_string(table.info().projector.width) + "x" +
                             std::to_string(table.info().projector.height) +
                             " projector, the display is " + std::to_string(projector.width) +
                             "x" + std::to_string(projector.height));
    return table;
}

void Scanner::reload_table(const fs::path& path) {
    CoefficientTable table = load_checked_table(path);
    const std::uint64_t hash = hash_file(path);
    // Only now: a bad file leaves the table in use as it was.
    table_ = std::move(table);
    table_file_hash_ = hash;
    table_path_ = path;
    log_.info("table " + path.string() + " loaded (" + to_string(table_.info().model) + ", hash " +
              hex64(table_file_hash_) + ")");
}

Frame Scanner::preview() {
    const bool software = board_.camera.settings.trigger == drivers::TriggerMode::software;
    dev_.camera.start();
    try {
        dev_.display.show(patterns_); // the white pattern after the sequence's
        const drivers::FlipEvent flip = dev_.display.wait_flip(board_.timing.flip_timeout);
        dev_.clock.sleep_until_ns(
            flip.timestamp_ns +
            std::chrono::duration_cast<std::chrono::nanoseconds>(board_.timing.settle).count());
        if (software)
            dev_.camera.software_trigger();
        else
            dev_.trigger.pulse(board_.timing.trigger_pulse);
        Frame frame = dev_.camera.next_frame(board_.camera.settings.frame_timeout).frame;
        dev_.camera.stop();
        return frame;
    } catch (...) {
        dev_.camera.stop();
        throw;
    }
}

ScanOutcome Scanner::scan(ScanMode mode, const std::atomic<bool>* stop, fs::path folder) {
    dev_.led.set(LedState::scanning);
    log_.info(std::string("scan started (") + (mode == ScanMode::scan ? "scan" : "capture") +
              " mode)");
    const auto fail = [&](const std::string& why, LedState led) {
        dev_.camera.stop();
        dev_.led.set(led);
        if (observer_)
            observer_->failed(why);
    };
    try {
        if (folder.empty()) {
            prepare_store(board_.store.directory);
            folder = new_scan_folder(board_.store.directory);
        }
    } catch (const std::exception& e) {
        log_.error(std::string("scan failed: ") + e.what());
        fail(e.what(), LedState::error);
        throw;
    }
    if (observer_)
        observer_->scan_started(folder.filename().string(), mode, static_cast<int>(patterns_));
    for (int attempt_no = 1;; ++attempt_no) {
        try {
            ScanOutcome outcome = attempt(mode, stop, folder);
            outcome.attempts = attempt_no;
            ++scans_completed_;
            dev_.led.set(LedState::ready);
            if (observer_)
                observer_->written(outcome);
            return outcome;
        } catch (const drivers::DeviceError& e) {
            if (attempt_no == 1 && e.device().find("camera") != std::string::npos) {
                dev_.camera.stop();
                log_.warning(std::string("scan attempt failed: ") + e.what() + "; retrying once");
                continue;
            }
            log_.error(std::string("scan failed: ") + e.what());
            fail(e.what(), LedState::error);
            throw;
        } catch (const ScanAborted&) {
            log_.warning("scan aborted by a stop request; nothing written");
            fail("aborted by a stop request", LedState::off);
            throw;
        } catch (const std::exception& e) {
            log_.error(std::string("scan failed: ") + e.what());
            fail(e.what(), LedState::error);
            throw;
        }
    }
}

ScanOutcome Scanner::attempt(ScanMode mode, const std::atomic<bool>* stop,
                             const fs::path& folder) {
    if (mode == ScanMode::scan && table_.empty())
        throw InputError(board_.file, "table", "scan mode needs a table (or use capture mode)");
    prepare_store(folder.parent_path());

    auto& clock = dev_.clock;
    const Size camera = dev_.camera.size();
    const std::int64_t settle_ns =
        std::chrono::duration_cast<std::chrono::nanoseconds>(board_.timing.settle).count();
    const bool software = board_.camera.settings.trigger == drivers::TriggerMode::software;

    ScanOutcome outcome;
    Captured captured;
    captured.started_utc = utc_text(std::time(nullptr));
    StreamingDecoder& decoder = *decoder_;
    decoder.restart(std::move(recycled_));
    double push_total = 0;

    dev_.camera.start();
    const std::int64_t capture_start = clock.now_ns();
    dev_.display.show(0);
    std::uint64_t previous_id = 0;
    for (std::size_t i = 0; i < patterns_; ++i) {
        const drivers::FlipEvent flip = dev_.display.wait_flip(board_.timing.flip_timeout);
        if (flip.index != i)
            throw PatternMismatch("flip event for pattern " + std::to_string(flip.index) +
                                  ", expected " + std::to_string(i));
        clock.sleep_until_ns(flip.timestamp_ns + settle_ns);
        if (software)
            dev_.camera.software_trigger();
        else
            dev_.trigger.pulse(board_.timing.trigger_pulse);
        drivers::CapturedFrame frame = dev_.camera.next_frame(board_.camera.settings.frame_timeout);
        if (i > 0 && frame.frame_id != previous_id + 1)
            throw drivers::DeviceError("camera", "frame id " + std::to_string(frame.frame_id) +
                                                     " after " + std::to_string(previous_id) +
                                                     ": a frame was dropped");
        previous_id = frame.frame_id;
        // The exposure must start after the pattern is on screen (both on the
        // scan clock; a camera that cannot tell reports 0).
        if (frame.timestamp_ns != 0 && frame.timestamp_ns < flip.timestamp_ns)
            throw PatternMismatch("frame " + std::to_string(frame.frame_id) +
                                  " exposed before pattern " + std::to_string(i) +
                                  " was on screen");
        if (frame.frame.size() != camera)
            throw drivers::DeviceError("camera", "frame of the wrong size");
        captured.records.push_back({flip, frame.frame_id, frame.timestamp_ns});
        // The next pattern flips while this frame is decoded.
        if (i + 1 < patterns_)
            dev_.display.show(i + 1);
        if (observer_)
            observer_->frame_captured(static_cast<int>(i + 1), static_cast<int>(patterns_));
        const double t0 = wall_ms();
        decoder.push(frame.frame);
        const double dt = wall_ms() - t0;
        push_total += dt;
        outcome.timings.push_max_ms = std::max(outcome.timings.push_max_ms, dt);
        if (mode == ScanMode::capture)
            captured.frames.push_back(std::move(frame.frame));
        if (stop && stop->load())
            throw ScanAborted();
    }
    dev_.camera.stop();
    const double last_frame = wall_ms();
    outcome.timings.capture_ms = static_cast<double>(clock.now_ns() - capture_start) / 1e6;
    outcome.timings.push_mean_ms = push_total / static_cast<double>(patterns_);
    outcome.frames = static_cast<int>(patterns_);

    double t = wall_ms();
    DecodeResult decoded = decoder.finish();
    outcome.timings.finish_ms = wall_ms() - t;
    if (observer_)
        observer_->decoded();

    t = wall_ms();
    write_folder_atomically(folder, [&](const fs::path& temp) {
        write_outputs(temp, mode, captured, decoded, outcome);
    });
    const double written = wall_ms();
    outcome.timings.write_ms = written - t - outcome.timings.apply_ms;
    outcome.timings.last_frame_to_written_ms = written - last_frame;
    outcome.folder = folder;
    recycled_ = std::move(decoded);

    if (folder.parent_path() == board_.store.directory) {
        const auto removed = prune_store(board_.store.directory, board_.store.max_bytes, folder);
        for (const auto& r : removed)
            log_.info("store full: removed " + r.filename().string());
    }
    char line[200];
    std::snprintf(line, sizeof line,
                  "scan written: %zu points, %d frames, streaming %.2f ms/frame (max %.2f), "
                  "last frame to disk %.1f ms",
                  outcome.points, outcome.frames, outcome.timings.push_mean_ms,
                  outcome.timings.push_max_ms, outcome.timings.last_frame_to_written_ms);
    log_.info(std::string(line) + " -> " + folder.string());
    return outcome;
}

void Scanner::write_outputs(const fs::path& temp, ScanMode mode, Captured& captured,
                            DecodeResult& decoded, ScanOutcome& outcome) {
    const Size camera = dev_.camera.size();
    const Size projector = dev_.display.size();
    if (!table_.empty()) {
        const double t = wall_ms();
        const Image<float>& phase =
            table_.info().phase_axis == Axis::x ? decoded.proj_x : decoded.proj_y;
        if (phase.empty())
            throw InputError(table_path_, "phase_axis",
                             std::string("the sequence codes no ") +
                                 to_string(table_.info().phase_axis) + " phase");
        // cloud_ keeps its memory from the previous scan: a fresh 23 MB
        // cloud costs the kernel's page faults on every scan.
        const TableApplyStats stats = apply_table(table_, phase, cloud_);
        outcome.points = stats.points;
        outcome.timings.apply_ms = wall_ms() - t;
        // The cloud borrows the decoder's B and A images for the PLY rather
        // than copying 15 MB (at 1600x1200); they go back to be recycled,
        // also when the write fails.
        cloud_.quality = std::move(decoded.modulation);
        cloud_.intensity = std::move(decoded.mean);
        const auto give_back = [&] {
            decoded.modulation = std::move(cloud_.quality);
            decoded.mean = std::move(cloud_.intensity);
        };
        try {
            write_ply_synced(temp / "cloud.ply", cloud_,
                             {"fpp-scanner board " + board_.name, "scan " + captured.started_utc});
        } catch (...) {
            give_back();
            throw;
        }
        give_back();
    }
    if (mode == ScanMode::capture) {
        CaptureManifest manifest;
        manifest.camera = camera;
        manifest.projector = projector;
        for (std::size_t i = 0; i < captured.frames.size(); ++i) {
            char name[32];
            std::snprintf(name, sizeof name, "%03zu.png", i);
            manifest.frames.emplace_back(name);
        }
        manifest.sequence = sequence_;
        manifest.metadata_yaml = "board: " + yaml_fields::format_string(board_.name) +
                                 "\nscanned_utc: " + captured.started_utc;
        write_capture_set(temp / "capture", manifest, captured.frames);
    }

    std::optional<TableSummary> table;
    if (!table_.empty())
        table = TableSummary{table_path_, table_.info().model, table_file_hash_,
                             table_.info().calibration_hash};
    const ScanMetadata metadata{board_,           mode,
                                captured.started_utc, camera,
                                dev_.camera.bit_depth(), projector,
                                table,            decoded.method_x,
                                decoded.method_y, outcome,
                                captured.records};
    write_file_synced(temp / "scan.json", scan_json(metadata));
}

} // namespace fpp::scanner
