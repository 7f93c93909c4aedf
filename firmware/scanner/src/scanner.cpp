#include "fpp/scanner/scanner.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/drivers/device_error.hpp"
#include "fpp/drivers/gige_frame_ids.hpp"
#include "fpp/error.hpp"
#include "fpp/fnv1a.hpp"
#include "fpp/patterns.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/projector_response.hpp"
#include "fpp/scanner/exposure_plan.hpp"
#include "fpp/scanner/scan_store.hpp"
#include "fpp/table_kernel.hpp"
#include "fpp/yaml_fields.hpp"
#include "scan_metadata.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>

#include <sys/stat.h>

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

std::optional<Scanner::FileStamp> Scanner::stamp_of(const fs::path& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0)
        return std::nullopt;
    return FileStamp{static_cast<std::uint64_t>(st.st_dev), static_cast<std::uint64_t>(st.st_ino),
                     static_cast<std::int64_t>(st.st_size),
                     std::int64_t{st.st_mtim.tv_sec} * 1'000'000'000 + st.st_mtim.tv_nsec,
                     std::int64_t{st.st_ctim.tv_sec} * 1'000'000'000 + st.st_ctim.tv_nsec};
}

struct Scanner::Captured {
    std::vector<FrameRecord> records;
    std::vector<std::vector<Frame>> frames; // per pass, capture mode only
    std::string started_utc;
};

Scanner::Scanner(const BoardConfig& board, Devices devices, const Logger& log)
    : Scanner(board, ScannerSettings{board.camera.settings.exposure_us}, devices, log) {}

Scanner::Scanner(const BoardConfig& board, const ScannerSettings& settings, Devices devices,
                 const Logger& log)
    : board_(board), settings_(settings), dev_(devices), log_(log) {
    const Size projector = dev_.display.size();
    sequence_ = board_.sequence(projector);
    if (board_.table)
        reload_table(*board_.table);
    check_hdr_exposures(board_, dev_.camera.exposure_range_us());
    if (board_.projector_response) {
        // Fringes emitted as v^2 rather than v where the sequence allows it
        // (every phase block of 4 steps or more): the same amplitude in less
        // light, so less shot noise (fpp/patterns.hpp).
        response_lut_ = GammaLut::from_response(load_projector_response(*board_.projector_response),
                                                compensation_emitted_gamma(sequence_));
        log_.info("patterns rendered through the inverse of the projector response " +
                  board_.projector_response->string());
    }
    prepare_patterns();
    // Made now, so that a scan never starts on a sequence the decoder rejects.
    decoder_.emplace(sequence_, dev_.camera.size(), projector);
    log_.info("board " + board_.name + ": " + std::to_string(patterns_) + " patterns at " +
              std::to_string(projector.width) + "x" + std::to_string(projector.height) +
              ", camera " + std::to_string(dev_.camera.size().width) + "x" +
              std::to_string(dev_.camera.size().height));
}

void Scanner::prepare_patterns() {
    const Size projector = dev_.display.size();
    auto patterns =
        render_sequence(sequence_, projector, response_lut_ ? &*response_lut_ : nullptr);
    patterns_ = patterns.size();
    patterns.emplace_back(projector, 1, std::uint8_t{255}); // white, for previews
    dev_.display.prepare(patterns);
}

std::vector<Frame> Scanner::grab_prepared(std::size_t first, std::size_t count) {
    std::vector<Frame> frames;
    dev_.camera.start();
    try {
        for (std::size_t i = first; i < first + count; ++i) {
            dev_.display.show(i);
            const drivers::FlipEvent flip = dev_.display.wait_flip(board_.timing.flip_timeout);
            frames.push_back(trigger_and_take(flip, i).frame);
        }
        check_no_frame_waiting(
            [count] { return "after the last of " + std::to_string(count) + " frames"; });
        dev_.camera.stop();
        return frames;
    } catch (...) {
        dev_.camera.stop();
        throw;
    }
}

ResponseRamp Scanner::capture_ramp() {
    const Size projector = dev_.display.size();
    ResponseRamp ramp;
    ramp.levels = standard_ramp_levels();
    std::vector<Image<std::uint8_t>> patterns;
    for (int level : ramp.levels)
        patterns.push_back(ramp_pattern(level, projector));
    dev_.display.prepare(patterns);
    patterns.clear();
    try {
        ramp.frames = grab_prepared(0, ramp.levels.size());
    } catch (...) {
        prepare_patterns();
        throw;
    }
    prepare_patterns();
    log_.info("projector response ramp captured: " + std::to_string(ramp.levels.size()) +
              " grey levels");
    return ramp;
}

CoefficientTable Scanner::load_checked_table(const fs::path& path) const {
    const Size camera = dev_.camera.size();
    const Size projector = dev_.display.size();
    // Read, not mapped: a mapping follows writes into the file (a `cp` over
    // it truncates, then rewrites: SIGBUS on the pages past its end
    // meanwhile, and a mix of two tables after, unchecked).
    CoefficientTable table = load_table(path, &camera, /*map=*/false);
    if (table.info().projector != projector)
        throw InputError(path, "projector_size",
                         "table made for a " + std::to_string(table.info().projector.width) + "x" +
                             std::to_string(table.info().projector.height) +
                             " projector, the display is " + std::to_string(projector.width) + "x" +
                             std::to_string(projector.height));
    return table;
}

void Scanner::reload_table(const fs::path& path) {
    // Stamped first: a change while it loads is seen by the next scan.
    const std::optional<FileStamp> stamp = stamp_of(path);
    CoefficientTable table = load_checked_table(path);
    const std::uint64_t hash = hash_file(path);
    // Only now: a bad file leaves the table in use as it was.
    table_ = std::move(table);
    table_file_hash_ = hash;
    table_path_ = path;
    table_stamp_ = stamp;
    log_.info("table " + path.string() + " loaded (" + to_string(table_.info().model) + ", hash " +
              hex64(table_file_hash_) + ")");
}

void Scanner::reload_table_if_changed() {
    if (table_path_.empty() || stamp_of(table_path_) == table_stamp_)
        return;
    try {
        reload_table(table_path_);
    } catch (const std::exception&) {
        // The table in memory is no longer the file's: scanning on with it
        // would measure with a calibration that the person replaced.
        log_.error("table " + table_path_.string() +
                   " changed on disk and cannot be used (the scan's error says why); scans "
                   "stop until it is whole again or another is installed");
        throw;
    }
    log_.warning("table " + table_path_.string() + " changed on disk: reloaded");
}

void Scanner::apply_settings(const ScannerSettings& settings) {
    dev_.camera.set_exposure_us(settings.exposure_us);
    settings_ = settings;
}

Frame Scanner::preview_at(double exposure_us) {
    const double own = settings_.exposure_us;
    dev_.camera.set_exposure_us(exposure_us);
    try {
        Frame frame = preview();
        dev_.camera.set_exposure_us(own);
        return frame;
    } catch (...) {
        dev_.camera.set_exposure_us(own);
        throw;
    }
}

Frame Scanner::preview() {
    return std::move(grab_prepared(patterns_, 1).front()); // the white pattern after the sequence's
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
        if (mode == ScanMode::scan)
            reload_table_if_changed();
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
        observer_->scan_started(folder.filename().string(), mode, planned_frames());
    for (int attempt_no = 1;; ++attempt_no) {
        try {
            ScanOutcome outcome = attempt(mode, stop, folder);
            outcome.attempts = attempt_no;
            dev_.led.set(LedState::ready);
            if (observer_)
                observer_->written(outcome);
            return outcome;
        } catch (const drivers::DeviceError& e) {
            if (attempt_no == 1 && e.kind() == drivers::DeviceKind::camera) {
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

std::vector<double> Scanner::scan_exposures() {
    if (!board_.hdr)
        return {settings_.exposure_us};
    if (!board_.hdr->automatic)
        return board_.hdr->exposures_us;
    const HdrConfig& hdr = *board_.hdr;
    const double longest =
        hdr.longest_us.value_or(settings_.exposure_us * std::pow(hdr.ratio, hdr.passes - 1));
    const std::vector<double> chosen =
        automatic_exposures(hdr, longest, dev_.camera.exposure_range_us(),
                            [this](double exposure_us) { return preview_at(exposure_us); });
    std::string text;
    for (double e : chosen)
        text += (text.empty() ? "" : ", ") + yaml_fields::format_real(e);
    log_.info("hdr exposures chosen from previews: " + text + " us");
    return chosen;
}

namespace {

// Restores the camera's own exposure when an HDR scan ends, however it ends.
class ExposureRestorer {
public:
    ExposureRestorer(drivers::Camera& camera, double own) : camera_(camera), own_(own) {}
    ~ExposureRestorer() {
        if (changed_) {
            try {
                camera_.set_exposure_us(own_);
            } catch (...) {
                // The camera is gone: the next scan's start reports it.
            }
        }
    }
    ExposureRestorer(const ExposureRestorer&) = delete;
    ExposureRestorer& operator=(const ExposureRestorer&) = delete;
    void set(double exposure_us) {
        if (exposure_us == own_ && !changed_)
            return;
        camera_.set_exposure_us(exposure_us);
        changed_ = true;
    }

private:
    drivers::Camera& camera_;
    double own_;
    bool changed_ = false;
};

} // namespace

ScanOutcome Scanner::attempt(ScanMode mode, const std::atomic<bool>* stop, const fs::path& folder) {
    if (mode == ScanMode::scan && table_.empty())
        throw InputError(board_.file, "table", "scan mode needs a table (or use capture mode)");
    prepare_store(folder.parent_path());

    ScanOutcome outcome;
    Captured captured;
    captured.started_utc = utc_text(std::time(nullptr));
    outcome.exposures_us = scan_exposures();
    const int passes = static_cast<int>(outcome.exposures_us.size());
    if (passes_.size() != static_cast<std::size_t>(passes))
        passes_.resize(static_cast<std::size_t>(passes));
    ExposureRestorer exposure(dev_.camera, settings_.exposure_us);
    double push_total = 0;
    double finish_ms = 0;
    auto& clock = dev_.clock;
    const std::int64_t capture_start = clock.now_ns();
    double last_frame = 0;
    for (int p = 0; p < passes; ++p) {
        ExposurePass& pass = passes_[static_cast<std::size_t>(p)];
        pass.exposure_us = outcome.exposures_us[static_cast<std::size_t>(p)];
        exposure.set(pass.exposure_us);
        decoder_->restart(std::move(pass.decoded));
        capture_pass(p, passes, mode, stop, captured, outcome, push_total);
        last_frame = wall_ms();
        pass.decoded = decoder_->finish();
        finish_ms += wall_ms() - last_frame;
    }
    const int frames = static_cast<int>(patterns_) * passes;
    outcome.timings.capture_ms = static_cast<double>(clock.now_ns() - capture_start) / 1e6;
    outcome.timings.push_mean_ms = push_total / static_cast<double>(frames);
    outcome.timings.finish_ms = finish_ms;
    outcome.frames = frames;
    DecodeResult& decoded = combine_passes(outcome);
    if (observer_)
        observer_->decoded();

    const bool in_store = folder.parent_path() == board_.store.directory;
    const std::optional<GoodScan> last_good =
        in_store ? newest_good_scan(board_.store.directory, folder) : std::nullopt;
    double t = wall_ms();
    write_folder_atomically(folder, [&](const fs::path& temp) {
        write_outputs(temp, mode, captured, decoded, outcome, last_good);
    });
    const double written = wall_ms();
    outcome.timings.write_ms = written - t - outcome.timings.apply_ms;
    outcome.timings.last_frame_to_written_ms = written - last_frame;
    outcome.folder = folder;

    if (in_store) {
        const auto removed = prune_store(board_.store.directory, board_.store.max_bytes, folder);
        for (const auto& r : removed)
            log_.info("store full: removed " + r.filename().string());
    }
    char line[240];
    std::snprintf(line, sizeof line,
                  "scan written: %zu points, %d frames in %d pass%s, streaming %.2f ms/frame "
                  "(max %.2f), last frame to disk %.1f ms",
                  outcome.points, outcome.frames, passes, passes == 1 ? "" : "es",
                  outcome.timings.push_mean_ms, outcome.timings.push_max_ms,
                  outcome.timings.last_frame_to_written_ms);
    log_.info(std::string(line) + " -> " + folder.string());
    return outcome;
}

template <class Where> void Scanner::check_no_frame_waiting(Where&& where) const {
    if (const std::size_t extra = dev_.camera.frames_waiting(); extra != 0)
        throw drivers::DeviceError(drivers::DeviceKind::camera, "camera",
                                   std::to_string(extra) + " frame(s) that no trigger asked for, " +
                                       where() + " (a trigger fired twice)");
}

drivers::CapturedFrame Scanner::trigger_and_take(const drivers::FlipEvent& flip,
                                                 std::size_t pattern) {
    // (Named only when refused: no string is built for a good frame.)
    const auto name = [pattern] { return "pattern " + std::to_string(pattern); };
    dev_.clock.sleep_until_ns(
        flip.timestamp_ns +
        std::chrono::duration_cast<std::chrono::nanoseconds>(board_.timing.settle).count());
    check_no_frame_waiting([&] { return "before " + name() + "'s trigger"; });
    const bool software = board_.camera.settings.trigger == drivers::TriggerMode::software;
    const std::int64_t triggered_ns = dev_.clock.now_ns();
    if (software)
        dev_.camera.software_trigger();
    else
        dev_.trigger.pulse(board_.timing.trigger_pulse);
    drivers::CapturedFrame frame = dev_.camera.next_frame(board_.camera.settings.frame_timeout);
    // Timestamps are on the scan clock; a camera that cannot tell reports 0.
    // A software-triggered frame whose exposure started before its trigger
    // was sent belongs to an earlier, repeated trigger (its frame id follows
    // on, so only the time tells).
    if (software && frame.timestamp_ns != 0 && frame.timestamp_ns < triggered_ns)
        throw drivers::DeviceError(drivers::DeviceKind::camera, "camera",
                                   "frame " + std::to_string(frame.frame_id) +
                                       " was exposed before " + name() +
                                       "'s trigger was sent (a trigger fired twice)");
    // A line-triggered frame exposed before its pattern was on screen: the
    // trigger line is not the one the board file names, or fires early.
    if (frame.timestamp_ns != 0 && frame.timestamp_ns < flip.timestamp_ns)
        throw PatternMismatch("frame " + std::to_string(frame.frame_id) + " exposed before " +
                              name() + " was on screen");
    return frame;
}

void Scanner::capture_pass(int pass, int passes, ScanMode mode, const std::atomic<bool>* stop,
                           Captured& captured, ScanOutcome& outcome, double& push_total) {
    const Size camera = dev_.camera.size();
    const int total = static_cast<int>(patterns_) * passes;
    StreamingDecoder& decoder = *decoder_;
    if (mode == ScanMode::capture)
        captured.frames.emplace_back();

    dev_.camera.start();
    dev_.display.show(0);
    std::uint64_t previous_id = 0;
    for (std::size_t i = 0; i < patterns_; ++i) {
        const drivers::FlipEvent flip = dev_.display.wait_flip(board_.timing.flip_timeout);
        if (flip.index != i)
            throw PatternMismatch("flip event for pattern " + std::to_string(flip.index) +
                                  ", expected " + std::to_string(i));
        drivers::CapturedFrame frame = trigger_and_take(flip, i);
        // (A 16-bit GigE Vision counter goes from 65535 to 1.)
        if (i > 0 && drivers::gige_frames_missed(previous_id, frame.frame_id) != 0)
            throw drivers::DeviceError(drivers::DeviceKind::camera, "camera",
                                       "frame id " + std::to_string(frame.frame_id) + " after " +
                                           std::to_string(previous_id) + ": a frame was dropped");
        previous_id = frame.frame_id;
        if (frame.frame.size() != camera)
            throw drivers::DeviceError(drivers::DeviceKind::camera, "camera",
                                       "frame of the wrong size");
        captured.records.push_back({flip, frame.frame_id, frame.timestamp_ns});
        // The next pattern flips while this frame is decoded.
        if (i + 1 < patterns_)
            dev_.display.show(i + 1);
        if (observer_)
            observer_->frame_captured(pass * static_cast<int>(patterns_) + static_cast<int>(i) + 1,
                                      total);
        const double t0 = wall_ms();
        decoder.push(frame.frame);
        const double dt = wall_ms() - t0;
        push_total += dt;
        outcome.timings.push_max_ms = std::max(outcome.timings.push_max_ms, dt);
        if (mode == ScanMode::capture)
            captured.frames.back().push_back(std::move(frame.frame));
        if (stop && stop->load())
            throw ScanAborted();
    }
    check_no_frame_waiting(
        [this] { return "after the last of " + std::to_string(patterns_) + " frames"; });
    dev_.camera.stop();
}

PhaseNoiseModel Scanner::noise_model() const {
    // Without a measured noise the passes are still ranked by their
    // modulation: a nominal 1 DN of read noise orders them as their phase
    // noise would (the sigma is then not written).
    const CameraNoise camera = board_.camera.noise.value_or(CameraNoise{1.0, 0.0, 8});
    const Axis axis = table_.empty() ? Axis::x : table_.info().phase_axis;
    return phase_noise_model(sequence_, axis, camera, dev_.camera.bit_depth());
}

DecodeResult& Scanner::combine_passes(ScanOutcome& outcome) {
    const PhaseNoiseModel model = noise_model();
    if (passes_.size() == 1) {
        DecodeResult& decoded = passes_[0].decoded;
        if (board_.camera.noise)
            coordinate_sigma(decoded.modulation, decoded.mean, model, sigma_);
        outcome.has_sigma = board_.camera.noise.has_value();
        return decoded;
    }
    const double t = wall_ms();
    for (ExposurePass& pass : passes_)
        coordinate_sigma(pass.decoded.modulation, pass.decoded.mean, model, pass.sigma);
    outcome.fusion = fuse_exposures(passes_, fused_, sigma_);
    outcome.timings.fuse_ms = wall_ms() - t;
    outcome.has_sigma = board_.camera.noise.has_value();
    return fused_;
}

void Scanner::write_outputs(const fs::path& temp, ScanMode mode, Captured& captured,
                            DecodeResult& decoded, ScanOutcome& outcome,
                            const std::optional<GoodScan>& last_good) {
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
        const TableApplyStats stats =
            apply_table(table_, phase, cloud_, nullptr, outcome.has_sigma ? &sigma_ : nullptr);
        outcome.points = stats.points;
        if (outcome.has_sigma && board_.points.max_sigma_z_mm) {
            outcome.dropped_by_sigma =
                drop_points_above_sigma(cloud_, static_cast<float>(*board_.points.max_sigma_z_mm));
            outcome.points -= outcome.dropped_by_sigma;
        }
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
    // Capture mode: the raw frames as capture sets, capture/ for the first
    // pass, capture-2/, capture-3/, ... for the other exposures of HDR.
    for (std::size_t p = 0; mode == ScanMode::capture && p < captured.frames.size(); ++p) {
        CaptureManifest manifest;
        manifest.camera = camera;
        manifest.projector = projector;
        for (std::size_t i = 0; i < captured.frames[p].size(); ++i) {
            char name[32];
            std::snprintf(name, sizeof name, "%03zu.png", i);
            manifest.frames.emplace_back(name);
        }
        manifest.sequence = sequence_;
        manifest.metadata_yaml = "board: " + yaml_fields::format_string(board_.name) +
                                 "\nscanned_utc: " + captured.started_utc + "\nexposure_us: " +
                                 yaml_fields::format_real(outcome.exposures_us[p]);
        const std::string name = p == 0 ? "capture" : "capture-" + std::to_string(p + 1);
        write_capture_set(temp / name, manifest, captured.frames[p]);
    }

    std::optional<TableSummary> table;
    if (!table_.empty())
        table = TableSummary{table_path_, table_.info().model, table_file_hash_,
                             table_.info().calibration_hash, table_.info().trueness};
    // The decode statistics of scan.json: of the result the cloud comes from.
    const double full_scale = dev_.camera.bit_depth() == 8 ? 255.0 : 65535.0;
    const bool fused = passes_.size() > 1;
    std::vector<const DecodeResult*> pass_results;
    for (const ExposurePass& pass : passes_)
        pass_results.push_back(&pass.decoded);
    const DecodeStatistics statistics =
        fused ? fused_decode_statistics(decoded, pass_results, full_scale)
              : decode_statistics(decoded, full_scale);
    outcome.verdict = judge_scan(
        {statistics, outcome.points, mode == ScanMode::scan,
         *std::max_element(outcome.exposures_us.begin(), outcome.exposures_us.end()), last_good});
    if (!outcome.verdict.good)
        log_.warning("poor scan: " + outcome.verdict.reasons.front() + ". " +
                     outcome.verdict.advice);
    const ScanMetadata metadata{board_,
                                settings_,
                                mode,
                                captured.started_utc,
                                camera,
                                dev_.camera.bit_depth(),
                                projector,
                                table,
                                decoded.method_x,
                                decoded.method_y,
                                outcome,
                                captured.records,
                                statistics,
                                fused ? "fused" : "pass"};
    write_file_synced(temp / "scan.json", scan_json(metadata));
}

} // namespace fpp::scanner
