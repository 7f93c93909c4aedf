// fpp-calib correct --artefact FILE --calib CALIB.yaml --session SESSION
//     --table TABLE.fpt --out-calib OUT.yaml --out-table OUT.fpt CAPTURE...
//     [--held-out CAPTURE...] [--report DIR]
//
// In-field correction of the depth scale with a certified ball bar: the
// used CAPTUREs are measured with TABLE as `verify` measures them
// (capture_measurement.hpp), the depth scale k that makes their lengths
// match the certificate is fitted (fpp/calib/depth_scale.hpp), the session
// is calibrated again camera first with the camera's focal lengths scaled
// (StereoOptions::camera_focal_scale), the table refitted from the same
// poses, and the used positions measured again; repeated while the
// remaining correction is above its noise (3 rounds at most: one step
// leaves about 8 % of the error, a rigid board placed again keeping its
// own depth extent). The held-out positions are verified with the old and
// the new table. Both outputs are written only when everything succeeded.
// Exit status: 0, 2 for bad input or a refused correction (nothing
// written), 3 when a capture does not decode.

#include "calibration_outputs.hpp"
#include "capture_measurement.hpp"
#include "cli_util.hpp"
#include "commands.hpp"
#include "correct_report.hpp"
#include "decode_outputs.hpp"

#include "fpp/calib/artefact.hpp"
#include "fpp/calib/depth_scale.hpp"
#include "fpp/calib/hybrid_calibrate.hpp"
#include "fpp/calib/plots.hpp"
#include "fpp/calib/report_folder.hpp"
#include "fpp/calib/session_folder.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/stereo_session.hpp"
#include "fpp/calib/verification.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/error.hpp"
#include "fpp/fnv1a.hpp"

#include <cmath>
#include <fstream>
#include <iostream>
#include <optional>
#include <unistd.h>

namespace fpp::calib {

namespace {

namespace fs = std::filesystem;

constexpr int kMaxCorrectionRounds = 3;

struct CorrectArgs {
    std::string artefact, calib, session, table, out_calib, out_table, report;
    std::vector<std::string> captures, held_out;
    DecodeOptions decode;
};

// An output file: must not exist, its folder must exist and be writable.
void check_new_output(const fs::path& path, const char* option) {
    if (fs::exists(path))
        throw InputError(path, option, "already exists; correct never overwrites a calibration");
    const fs::path parent = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    if (!fs::is_directory(parent))
        throw InputError(path, option, "the folder " + parent.string() + " does not exist");
    if (::access(parent.c_str(), W_OK) != 0)
        throw InputError(path, option, "the folder " + parent.string() + " cannot be written");
}

void check_correct_arguments(const CorrectArgs& args) {
    check_decode_options(args.decode);
    check_new_output(args.out_calib, "--out-calib");
    check_new_output(args.out_table, "--out-table");
    if (fs::weakly_canonical(args.out_calib) == fs::weakly_canonical(args.out_table))
        throw InputError(args.out_table, "--out-table", "the same file as --out-calib");
    if (!args.report.empty() && !report_folder_writable(args.report))
        throw InputError(args.report, "--report",
                         "exists and is not an earlier report (no summary.md); choose another "
                         "folder");
    std::vector<std::string> all = args.captures;
    all.insert(all.end(), args.held_out.begin(), args.held_out.end());
    for (std::size_t i = 0; i < all.size(); ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (fs::weakly_canonical(all[i]) == fs::weakly_canonical(all[j]))
                throw InputError(all[i], "",
                                 "given twice: each capture is one position, used or held out");
    if (!fs::is_regular_file(args.table))
        throw InputError(args.table, "--table", "no such file");
}

// The session must be the one the calibration was made from, as far as its
// files tell: the same camera and projector sizes and board squares.
SessionFolder check_session(const fs::path& session, const StereoCalibration& calibration,
                            const fs::path& calibration_path) {
    SessionFolder folder = read_session_folder(
        session, BoardDescription::Kind::checkerboard, {Axis::x, Axis::y}, "correction",
        "the stereo calibration needs both projector coordinates");
    const fs::path first = folder.poses.front() / "capture.yaml";
    if (folder.camera_size != calibration.camera_size)
        throw InputError(first, "camera",
                         "camera " + std::to_string(folder.camera_size.width) + " x " +
                             std::to_string(folder.camera_size.height) + " but " +
                             calibration_path.string() + " is for " +
                             std::to_string(calibration.camera_size.width) + " x " +
                             std::to_string(calibration.camera_size.height) +
                             ": not the session of this calibration");
    if (folder.projector_size != calibration.projector_size)
        throw InputError(first, "projector",
                         "projector size differs from " + calibration_path.string() +
                             "'s: not the session of this calibration");
    const double square = folder.board.square_size, made = calibration.board_square_size;
    if (made > 0 && std::abs(square - made) > 0.002 * made)
        throw InputError(session / "board.yaml", "square_size",
                         fixed_text(square, 3) + " mm but " + calibration_path.string() +
                             " was made with " + fixed_text(made, 3) +
                             " mm squares: not the session of this calibration");
    return folder;
}

// The used positions measured with `table`: their centre vectors. Nothing
// when a decode failed.
std::optional<std::vector<LengthObservation>>
measure_used(const CorrectArgs& args, const CaptureMeasurement& how, const Artefact& artefact,
             std::optional<CoefficientTable>& table,
             std::vector<MeasuredPosition>* kept = nullptr) {
    const VerificationOptions options;
    std::vector<LengthObservation> used;
    std::vector<MeasuredPosition> positions;
    for (std::size_t k = 0; k < args.captures.size(); ++k) {
        std::optional<MeasuredPosition> p =
            measure_capture(args.captures[k], how, artefact, table, options);
        if (!p)
            return std::nullopt;
        std::cerr << "  " << position_line(k, *p) << "\n";
        const Vec3 a = p->spheres.at(0).centre, b = p->spheres.at(1).centre;
        used.push_back({args.captures[k], Vec3{b[0] - a[0], b[1] - a[1], b[2] - a[2]}});
        positions.push_back(std::move(*p));
    }
    if (kept)
        *kept = std::move(positions);
    return used;
}

// The held-out positions verified with one table, as `verify` would.
std::optional<VerificationRecord> verify_held_out(const CorrectArgs& args,
                                                  const CaptureMeasurement& how,
                                                  const Artefact& artefact,
                                                  std::optional<CoefficientTable>& table) {
    VerificationRecord record;
    record.artefact = artefact;
    record.table = how.table_path;
    for (const std::string& capture : args.held_out) {
        std::optional<MeasuredPosition> p =
            measure_capture(capture, how, artefact, table, record.options);
        if (!p)
            return std::nullopt;
        record.positions.push_back(std::move(*p));
    }
    record.figures = verdicts(artefact, record.positions, record.options.mpe);
    return record;
}

// The table fitted from the session's boards with `calibration` (its
// header: the calibration's trueness and the hash of its file's bytes).
void refit_table(const CorrectArgs& args, const StereoCalibration& calibration,
                 const HybridOptions& hybrid, const std::vector<BoardView>& views,
                 std::optional<CoefficientTable>& table) {
    const std::string bytes = calibration_to_yaml(calibration);
    std::vector<HybridResult> results =
        calibrate_hybrid(args.session, calibration, fnv1a64(bytes.data(), bytes.size()), hybrid,
                         {hybrid.model}, views);
    table.reset();
    table.emplace(std::move(results.front().table));
}

// The calibration and the table, or neither: the table last, the
// calibration removed if it fails.
void write_outputs(const CorrectArgs& args, const StereoCalibration& calibration,
                   const CoefficientTable& table) {
    save_calibration(args.out_calib, calibration);
    try {
        write_table(args.out_table, table);
    } catch (...) {
        std::error_code ignored;
        fs::remove(args.out_calib, ignored);
        throw;
    }
}

int run_correct(const CorrectArgs& args) {
    check_correct_arguments(args);
    const Artefact artefact = read_artefact(args.artefact);
    if (artefact.kind != ArtefactKind::ball_bar)
        throw InputError(args.artefact, "kind",
                         std::string("a ") + to_string(artefact.kind) +
                             " has no certified length: correct needs a ball bar");
    const StereoCalibration input = load_calibration(args.calib);
    check_session(args.session, input, args.calib);
    const double certified = artefact.centre_distance_mm, u = artefact.uncertainty_mm;

    CorrectionRecord record;
    record.artefact = args.artefact;
    record.calibration = args.calib;
    record.session = args.session;
    record.table = args.table;
    record.out_calibration = args.out_calib;
    record.out_table = args.out_table;
    record.predicted = input.trueness;
    for (const std::string& c : args.captures)
        record.used.emplace_back(c);

    // Round 0: the input table.
    CaptureMeasurement old_table;
    old_table.table_path = args.table;
    old_table.table_hash = file_hash(args.table);
    old_table.decode = args.decode;
    std::optional<CoefficientTable> input_table;
    std::cerr << "== round 0: the used positions with " << args.table << "\n";
    std::vector<MeasuredPosition> measured;
    std::optional<std::vector<LengthObservation>> used =
        measure_used(args, old_table, artefact, input_table, &measured);
    if (!used)
        return kExitDecodeFailed;
    DepthScaleFit fit = fit_depth_scale(*used, certified, u);
    check_depth_scale_fit(fit, *used, input.trueness, certified, u, args.artefact, args.calib);
    check_certificate(artefact, measured, VerificationOptions{});
    std::cerr << "  " << depth_scale_text(fit) << "\n";
    record.rounds.push_back({1, fit});

    // The session, read once: the stereo calibration's observations and
    // the table's view of each board, as `calibrate` keeps them.
    HybridOptions hybrid;
    hybrid.decode = args.decode;
    hybrid.threads = args.decode.threads;
    hybrid.sv.threads = args.decode.threads;
    hybrid.progress = [](const std::string& line) { std::cerr << "  " << line << "\n"; };
    StereoSessionOptions stereo;
    stereo.decode = hybrid.decode;
    // A correction within its noise is not made (the smallest model the
    // lengths support is none): the session is calibrated as it was, and
    // the artefact only sets the trueness.
    const bool significant = std::abs(fit.scale - 1) > 2 * fit.sigma;
    double scale = significant ? fit.scale : 1;
    if (!significant)
        std::cerr << "  within 2 sigma of none: no correction, the trueness from the artefact\n";
    stereo.stereo.camera_focal_scale = scale;
    std::vector<BoardView> views;
    keep_board_views(args.session, hybrid, stereo, views);
    std::cerr << "== round 1: the session calibrated with the camera's focal lengths x "
              << fixed_text(scale, 6) << "\n";
    SessionResult session = calibrate_session(args.session, stereo);

    StereoCalibration calibration;
    std::optional<CoefficientTable> table;
    for (int round = 1;; ++round) {
        calibration = session_calibration(session);
        refit_table(args, calibration, hybrid, views, table);
        CaptureMeasurement refitted;
        refitted.table_path = args.out_table + " (round " + std::to_string(round) + ")";
        refitted.decode = args.decode;
        std::cerr << "== round " << round << ": the used positions with the refitted table\n";
        used = measure_used(args, refitted, artefact, table);
        if (!used)
            return kExitDecodeFailed;
        fit = fit_depth_scale(*used, certified, u);
        std::cerr << "  " << depth_scale_text(fit) << "\n";
        record.rounds.push_back({scale, fit});
        record.converged = std::abs(fit.scale - 1) <= 2 * fit.sigma;
        if (record.converged || round == kMaxCorrectionRounds)
            break;
        scale *= fit.scale;
        stereo.stereo.camera_focal_scale = scale;
        std::cerr << "== round " << round + 1 << ": the camera's focal lengths x "
                  << fixed_text(scale, 6) << "\n";
        session.stereo = stereo_calibrate(session.observations, session.camera_size,
                                          session.projector_size, stereo.stereo);
    }
    record.final_focal_scale = scale;

    // The trueness the artefact shows, in the calibration and the table's
    // header (with the hash of the calibration file's bytes).
    record.corrected = trueness_from_fit(calibration.trueness, fit, certified);
    calibration.trueness = record.corrected;
    DepthCorrection applied;
    applied.focal_scale = scale; // 1: within its noise, none made
    applied.before_ppm = record.rounds.front().fit.correction_ppm();
    applied.before_sigma_ppm = record.rounds.front().fit.sigma * 1e6;
    applied.after_ppm = fit.correction_ppm();
    applied.after_sigma_ppm = fit.sigma * 1e6;
    applied.positions = static_cast<int>(args.captures.size());
    applied.artefact = artefact.name.empty() ? args.artefact : artefact.name;
    calibration.depth_correction = applied;
    const std::string bytes = calibration_to_yaml(calibration);
    table->set_provenance(fnv1a64(bytes.data(), bytes.size()),
                          table_trueness(calibration.trueness));

    if (!args.held_out.empty()) {
        std::cerr << "== the held-out positions, with the input table and the corrected one\n";
        record.before = verify_held_out(args, old_table, artefact, input_table);
        CaptureMeasurement corrected;
        corrected.table_path = args.out_table;
        corrected.decode = args.decode;
        record.after = verify_held_out(args, corrected, artefact, table);
        if (!record.before || !record.after)
            return kExitDecodeFailed;
    }
    write_outputs(args, calibration, *table);
    if (!args.report.empty())
        write_correction_report(args.report, record);
    std::cout << correction_summary(record) << "wrote " << args.out_calib << " and "
              << args.out_table << (args.report.empty() ? "" : " and " + args.report) << "\n";
    return 0;
}

} // namespace

Action add_correct_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<CorrectArgs>(
        app, "correct",
        "Correct the calibration's depth scale with a certified ball bar: measure it in the "
        "used positions, fit the depth scale, calibrate the session again with the camera's "
        "focal lengths scaled (camera first), refit the table, repeat (3 rounds at most); "
        "verify the held-out positions before and after. Refuses a certificate or captures "
        "the lengths contradict, and positions that do not reach in depth",
        run_correct);
    cmd->add_option("captures", args->captures,
                    "capture set folders of the positions used for the correction (at least 2 "
                    "reaching in depth)")
        ->required();
    cmd->add_option("--held-out", args->held_out,
                    "capture set folders of positions left out of the correction, verified "
                    "before and after");
    cmd->add_option("--artefact", args->artefact, "the ball bar's certificate (fpp-artefact/1)")
        ->required();
    cmd->add_option("--calib", args->calib, "the calibration file to correct")->required();
    cmd->add_option("--session", args->session,
                    "the checkerboard session the calibration was made from")
        ->required();
    cmd->add_option("--table", args->table, "the table the captures were measured with (.fpt)")
        ->required();
    cmd->add_option("--out-calib", args->out_calib, "corrected calibration file to write (new)")
        ->required();
    cmd->add_option("--out-table", args->out_table, "refitted table to write (new)")->required();
    cmd->add_option("--report", args->report, "report folder (summary.md, before/, after/)");
    add_min_modulation_option(*cmd, args->decode.min_modulation);
    add_threads_option(*cmd, args->decode.threads);
    return action;
}

} // namespace fpp::calib
