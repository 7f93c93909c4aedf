// fpp-calib reconstruct CAPTURE (--calib FILE | --table table.fpt) --out cloud.ply
//                       [--xyz xyz.tiff] [--smooth RADIUS [--smooth-tolerance PX]]
//                       [--correct-phase-error]
//
// Decodes a capture set and reconstructs it with the stereo (SV) model of a
// calibration file: ours, SLStudio's calibration.xml or SLMaster's
// caliInfo.yml; or with a hybrid coefficient table (fpp/table_kernel.hpp,
// vertical fringes: the projector column only); optionally with the decoded
// projector coordinates smoothed first (edge-preserving,
// fpp/coordinate_filter.hpp). Outputs (written only when everything
// succeeded, never an empty cloud):
//   cloud.ply  binary little-endian PLY of the valid points (fpp/point_cloud.hpp)
//   xyz.tiff   optional: 3-channel float32 X, Y, Z per camera pixel, mm, NaN = none

#include "cli_util.hpp"
#include "cmd_reconstruct_pair.hpp"
#include "commands.hpp"
#include "decode_outputs.hpp"
#include "field_orientation.hpp"
#include "table_reconstruction.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/coordinate_filter.hpp"
#include "fpp/decode_diagnosis.hpp"
#include "fpp/decode_report.hpp"
#include "fpp/decoder.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/parallel.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/table_kernel.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <variant>

namespace fpp::calib {

namespace {

namespace fs = std::filesystem;

struct ReconstructArgs {
    std::string capture;
    std::string calib;
    std::string table;
    std::string calib_format = "auto";
    std::string out;
    std::string xyz;
    std::string axes = "auto";
    std::string camera_size;    // "WxH", for calibrations without sizes
    std::string projector_size; // "WxH"
    DecodeOptions decode;
    CoordinateFilterOptions smooth;               // radius set to 0 (off) unless --smooth
    std::string second_capture, pair_calibration; // two cameras: cmd_reconstruct_pair.cpp
    bool accept_inconsistent = false;
};

// The key a calibration format stores a size under, for error messages.
std::string size_key(const StereoCalibration& c, bool camera) {
    if (c.format == CalibrationFormat::slstudio)
        return camera ? "frameWidth/frameHeight" : "screenResX/screenResY";
    return camera ? "camera_size" : "projector_size";
}

// Sizes missing from the calibration (SLMaster) come from the options or the capture.
void settle_sizes(StereoCalibration& calibration, const fs::path& calib_path,
                  const ReconstructArgs& args, const CaptureManifest& manifest) {
    struct Item {
        Size& size;
        const std::string& option_text;
        const char* option;
        Size capture;
        bool camera;
    };
    for (Item item :
         {Item{calibration.camera_size, args.camera_size, "--camera-size", manifest.camera, true},
          Item{calibration.projector_size, args.projector_size, "--projector-size",
               manifest.projector, false}}) {
        const bool known = item.size.width > 0 && item.size.height > 0;
        if (!item.option_text.empty()) {
            const Size given = parse_size_text(item.option_text, item.option);
            if (known && given != item.size)
                throw InputError(calib_path, size_key(calibration, item.camera),
                                 std::string("the file says ") + size_text(item.size) + ", " +
                                     item.option + " says " + size_text(given));
            item.size = given;
        } else if (!known) {
            item.size = item.capture;
            std::cerr << "note: " << calib_path.string() << " records no "
                      << (item.camera ? "camera" : "projector") << " size; using the capture's "
                      << size_text(item.capture) << " (or give " << item.option << ")\n";
        }
    }
    if (calibration.camera_size != manifest.camera)
        throw InputError(calib_path, size_key(calibration, true),
                         "the calibration is for a " + size_text(calibration.camera_size) +
                             " camera, but the capture's frames are " + size_text(manifest.camera));
    if (calibration.projector_size != manifest.projector)
        throw InputError(calib_path, size_key(calibration, false),
                         "the calibration is for a " + size_text(calibration.projector_size) +
                             " projector, but the capture was projected at " +
                             size_text(manifest.projector));
}

// run_reconstruct's stages, in order.

// What the arguments ask for, checked before anything is read.
struct ReconstructRequest {
    CoordinateFilterOptions smooth; // --smooth, --smooth-tolerance; --threads
    fs::path out, xyz_out;
    ReconstructAxes requested = ReconstructAxes::automatic;
    CalibrationFormat format = CalibrationFormat::automatic;
    bool use_table = false; // --table, else --calib
    fs::path calib_path;    // the model's file
};

ReconstructRequest check_reconstruct_arguments(const ReconstructArgs& args) {
    CoordinateFilterOptions smooth = args.smooth;
    smooth.threads = args.decode.threads;
    try {
        smooth.validate();
    } catch (const std::invalid_argument& e) {
        throw InputError("command line", "--smooth", e.what());
    }
    const fs::path out = args.out;
    const fs::path xyz_out = args.xyz;
    check_output_path(out, "--out");
    if (!xyz_out.empty()) {
        check_output_path(xyz_out, "--xyz");
        if (fs::weakly_canonical(xyz_out) == fs::weakly_canonical(out))
            throw InputError(xyz_out, "--xyz", "same path as --out");
    }
    const ReconstructAxes requested = parse_axes(args.axes);
    const CalibrationFormat format = parse_calibration_format(args.calib_format);
    const bool use_table = !args.table.empty();
    if (use_table == !args.calib.empty())
        throw InputError("command line", "--calib/--table",
                         "give exactly one model: a stereo calibration (--calib) or a hybrid "
                         "coefficient table (--table)");
    if (use_table && requested == ReconstructAxes::xy)
        throw InputError("command line", "--axes",
                         "a coefficient table maps the projector column only (--axes x)");

    const fs::path calib_path = use_table ? fs::path(args.table) : fs::path(args.calib);
    return {smooth, out, xyz_out, requested, format, use_table, calib_path};
}

// The model, read and checked against the capture: a coefficient table
// (--table) or a stereo calibration (--calib), the other left empty.
struct ReconstructModel {
    StereoCalibration calibration;
    CoefficientTable table;
};

ReconstructModel load_reconstruct_model(const ReconstructArgs& args,
                                        const ReconstructRequest& request,
                                        const CaptureSet& capture) {
    const fs::path& calib_path = request.calib_path;
    ReconstructModel model;
    if (request.use_table) {
        CoefficientTable& table = model.table;
        table = load_table_for_capture(calib_path, capture);
        std::cerr << "table: " << to_string(table.info().model) << " model, camera "
                  << size_text(table.info().camera) << "\n";
    } else {
        StereoCalibration& calibration = model.calibration;
        calibration = load_calibration(calib_path, request.format);
        std::cerr << "calibration: " << calibration.origin << "\n";
        settle_sizes(calibration, calib_path, args, capture.manifest);
    }
    return model;
}

// The cloud the model makes of the decoded coordinates.
struct ModelledCloud {
    PointCloud cloud;
    SvStats stats;
    TableApplyStats table_stats; // with a table
    double prepare_seconds = 0, model_seconds = 0;
};

ModelledCloud apply_model(const ReconstructModel& model, bool use_table,
                          const DecodeResult& decoded, ReconstructAxes requested, int threads) {
    PointCloud cloud;
    SvStats stats;
    TableApplyStats table_stats;
    double prepare_seconds = 0, model_seconds = 0;
    if (use_table) {
        TableCloud made = apply_table_to_scan(model.table, decoded, threads);
        cloud = std::move(made.cloud);
        table_stats = made.stats;
        model_seconds = made.seconds;
        stats.axes = ReconstructAxes::x;
        stats.points = table_stats.points;
    } else {
        SvOptions sv;
        sv.threads = threads;
        Stopwatch prepare_watch;
        const SvReconstructor reconstructor(model.calibration, sv);
        prepare_seconds = prepare_watch.seconds();
        Stopwatch sv_watch;
        stats = reconstructor.reconstruct(decoded, requested, cloud);
        model_seconds = sv_watch.seconds();
    }
    return {std::move(cloud), stats, table_stats, prepare_seconds, model_seconds};
}

// Why no pixel gave a point (stderr).
void report_no_points(const CaptureSet& capture, const DecodedScan& scan,
                      const ReconstructRequest& request, const ModelledCloud& made) {
    const bool use_table = request.use_table;
    const fs::path& calib_path = request.calib_path;
    const DecodeStatistics& decode_stats = scan.decode_stats;
    const SvStats& stats = made.stats;
    const TableApplyStats& table_stats = made.table_stats;
    std::cerr << "fpp-calib: error: " << capture.folder.string() << ": " << decode_stats.decoded
              << " pixels decoded but none gave a point ("
              << (use_table
                      ? "no model " + std::to_string(table_stats.no_model) +
                            ", outside the calibrated phase range " +
                            std::to_string(table_stats.out_of_range) + " in " + calib_path.string()
                      : "outside the projector image " + std::to_string(stats.outside_projector) +
                            ", other geometry " + std::to_string(stats.rejected) +
                            ", not converged " + std::to_string(stats.not_converged) + " with " +
                            calib_path.string())
              << "): is the calibration for this scanner? no point cloud written\n";
}

// Writes the PLY (and the XYZ TIFF); the seconds it took.
double write_reconstruction(const ReconstructArgs& args, const ReconstructRequest& request,
                            const ReconstructModel& model, const ModelledCloud& made) {
    const bool use_table = request.use_table;
    const CoordinateFilterOptions& smooth = request.smooth;
    const fs::path &out = request.out, &xyz_out = request.xyz_out;
    const PointCloud& cloud = made.cloud;
    std::vector<std::string> comments = {
        use_table ? "fpp-calib reconstruct: hybrid model (" +
                        std::string(to_string(model.table.info().model)) +
                        " coefficient table), camera frame, mm"
                  : "fpp-calib reconstruct: stereo (SV) model, camera frame, mm",
        "capture " + fs::path(args.capture).filename().string() +
            (use_table ? ", table " : ", calibration ") + request.calib_path.filename().string() +
            ", axes " + to_string(made.stats.axes),
        "quality: fringe modulation (DN); intensity: mean intensity (DN); pixel: row * "
        "organised_width + column"};
    Stopwatch write_watch;
    if (smooth.radius > 0)
        comments.push_back("projector coordinates smoothed over " +
                           std::to_string(2 * smooth.radius + 1) + " x " +
                           std::to_string(2 * smooth.radius + 1) +
                           " px, edges kept (fpp-calib reconstruct --smooth)");
    // The TIFF is published inside the PLY's atomic write, just before the
    // PLY itself: a failure while writing either leaves neither.
    write_atomically(out, [&](const fs::path& temp) {
        write_ply_synced(temp, cloud, comments);
        if (!xyz_out.empty())
            write_tiff(xyz_out, cloud.xyz);
    });
    return write_watch.seconds();
}

// What was reconstructed, how, and how long it took (stdout).
std::string reconstruct_report(const ReconstructRequest& request, const CaptureSet& capture,
                               const DecodedScan& scan, const ModelledCloud& made,
                               double write_seconds) {
    const bool use_table = request.use_table;
    const CoordinateFilterOptions& smooth = request.smooth;
    const DecodeResult& decoded = scan.decoded;
    const DecodeStatistics& decode_stats = scan.decode_stats;
    const CoordinateFilterReport& smoothing = scan.smoothing;
    const PointCloud& cloud = made.cloud;
    const SvStats& stats = made.stats;
    const TableApplyStats& table_stats = made.table_stats;
    const CloudSummary z = summarise(cloud);
    const std::size_t pixels = cloud.xyz.pixel_count();
    std::ostringstream report;
    report << "axes: " << to_string(stats.axes) << " (decoded by " << decoded.method_x
           << (stats.axes == ReconstructAxes::xy ? " / " + decoded.method_y : std::string())
           << ")\n";
    if (smooth.radius > 0) {
        report << "smoothing: " << 2 * smooth.radius + 1 << " x " << 2 * smooth.radius + 1
               << " px, tolerance " << smoothing.tolerance_x;
        if (std::isfinite(smoothing.tolerance_y))
            report << " (x) / " << smoothing.tolerance_y << " (y)";
        report << " projector px"
               << (smooth.tolerance_px > 0 ? "" : " (5 x the noise estimated from the scan)")
               << "\n";
    }
    for (const auto* c : {&decoded.phase_correction_x, &decoded.phase_correction_y})
        if (c->attempted)
            report << "phase-error correction (" << (c == &decoded.phase_correction_x ? "x" : "y")
                   << "): " << describe(*c) << "\n";
    report << "decoded: " << decode_stats.decoded << " of " << decode_stats.lit << " lit pixels ("
           << 100.0 * decode_stats.coverage_of_lit() << " %); " << decode_stats.floor_rule()
           << "\n";
    report << "points: " << stats.points << " of " << pixels << " pixels ("
           << 100.0 * double(stats.points) / double(pixels) << " %); ";
    if (use_table)
        report << "decoded " << table_stats.phase_valid << "; no point: no model "
               << table_stats.no_model << ", outside the calibrated phase range "
               << table_stats.out_of_range << "\n";
    else
        report << "decoded " << stats.decoded << "; no point: outside the projector image "
               << stats.outside_projector << ", other geometry " << stats.rejected
               << ", not converged " << stats.not_converged << "\n";
    if (stats.points > 0)
        report << "depth Z: " << z.z_min << " .. " << z.z_max << " mm (1st-99th percentile "
               << z.z_p01 << " .. " << z.z_p99 << " mm)\n";
    if (!use_table && stats.axes == ReconstructAxes::x)
        report << "x-only solve: " << stats.mean_iterations() << " steps per point on average, at "
               << "most " << stats.max_iterations << "\n";
    else if (!use_table)
        report << "ray gap: RMS " << stats.rms_ray_gap_mm << " mm, max " << stats.max_ray_gap_mm
               << " mm\n";
    report << truth_comparison(cloud, capture);
    report << "time: decode " << scan.decode_seconds << " s, ";
    if (smooth.radius > 0)
        report << "smoothing " << scan.smooth_seconds << " s, ";
    if (use_table)
        report << "table " << made.model_seconds << " s, writing ";
    else
        report << "camera rays " << made.prepare_seconds << " s, SV " << made.model_seconds
               << " s, writing ";
    report << write_seconds << " s\n"
           << "wrote " << request.out.string()
           << (request.xyz_out.empty() ? "" : " and " + request.xyz_out.string()) << "\n";
    return report.str();
}

int run_reconstruct(const ReconstructArgs& args) {
    check_decode_options(args.decode);
    if (!args.second_capture.empty() || !args.pair_calibration.empty())
        return run_reconstruct_pair(
            {args.capture, args.second_capture,
             args.pair_calibration.empty() ? args.calib : args.pair_calibration, args.table,
             args.out, args.xyz, args.axes, args.decode});
    const ReconstructRequest request = check_reconstruct_arguments(args);
    std::cerr << "reading " << args.capture << "\n";
    const CaptureSet capture = read_capture_set(args.capture);
    const ReconstructModel model = load_reconstruct_model(args, request, capture);
    check_capture_axes(capture, request.requested);

    const std::optional<DecodedScan> scan =
        decode_and_smooth(capture, args.decode, request.smooth, args.accept_inconsistent);
    if (!scan)
        return kExitDecodeFailed;
    const ModelledCloud made = apply_model(model, request.use_table, scan->decoded,
                                           request.requested, args.decode.threads);
    if (made.stats.points == 0) {
        report_no_points(capture, *scan, request, made);
        return kExitDecodeFailed;
    }
    if (!request.use_table) {
        if (const auto why =
                mirrored_field(model.calibration, scan->decoded, made.stats.axes,
                               field_fit(made.stats, made.cloud), args.decode.threads)) {
            if (!args.accept_inconsistent)
                throw DecodeRefused(kExitInconsistent,
                                    capture.folder.string() + ": " + *why +
                                        "\nno point cloud written (--accept-inconsistent to "
                                        "write it as described)");
            std::cerr << "fpp-calib: warning: " << capture.folder.string() << ": " << *why << "\n";
        }
    }
    const double write_seconds = write_reconstruction(args, request, model, made);
    std::cout << reconstruct_report(request, capture, *scan, made, write_seconds);
    return 0;
}

} // namespace

Action add_reconstruct_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<ReconstructArgs>(
        app, "reconstruct",
        "Decode a capture set and reconstruct a point cloud with a stereo calibration (SV model, "
        "lens distortion compensated) or a hybrid coefficient table: binary PLY of the valid "
        "points, optional XYZ TIFF. Any sequence with a phase, micro phase or code block along "
        "x: phase families to a fraction of a projector pixel, a code-only sequence (Gray, "
        "n-ary, binary) at its code step (each pixel at its step's centre)",
        run_reconstruct);
    args->smooth.radius = 0;
    cmd->add_option("capture", args->capture, "capture set folder (holding capture.yaml)")
        ->required();
    cmd->add_option("--calib", args->calib,
                    "calibration file: fpp-calib's YAML, SLStudio's calibration.xml or "
                    "SLMaster's caliInfo.yml");
    cmd->add_option("--table", args->table,
                    "hybrid coefficient table (.fpt, from fpp-calib hybrid) instead of --calib");
    cmd->add_option("--second-capture", args->second_capture,
                    "the second camera's capture set of the same patterns: two-camera scanning "
                    "with a camera-camera calibration (--pair-calibration or --calib)");
    cmd->add_option("--pair-calibration", args->pair_calibration,
                    "camera-camera calibration (OpenCV stereo YAML, Bouguet or MATLAB text)");
    cmd->add_option("--calib-format", args->calib_format,
                    "format of --calib: auto (by its keys), fpp, slstudio, slmaster")
        ->check(CLI::IsMember({"auto", "fpp", "slstudio", "slmaster"}))
        ->capture_default_str();
    cmd->add_option("--out", args->out, "output point cloud (.ply)")->required();
    cmd->add_option("--xyz", args->xyz,
                    "also write X, Y, Z per camera pixel as a 3-channel float32 TIFF (mm, NaN "
                    "where no point)");
    cmd->add_option("--axes", args->axes,
                    "projector coordinates to use: auto (x and y when the capture codes both), "
                    "x (column only, distortion compensated iteratively), xy (ray midpoint)")
        ->check(CLI::IsMember({"auto", "x", "xy"}))
        ->capture_default_str();
    cmd->add_option("--camera-size", args->camera_size,
                    "camera WIDTHxHEIGHT for calibrations that do not record it (SLMaster); "
                    "default: the capture's");
    cmd->add_option("--projector-size", args->projector_size,
                    "projector WIDTHxHEIGHT for calibrations that do not record it (SLMaster); "
                    "default: the capture's");
    add_min_modulation_option(*cmd, args->decode.min_modulation);
    cmd->add_option("--smooth", args->smooth.radius,
                    "smooth the decoded projector coordinates over (2 RADIUS + 1)^2 camera "
                    "pixels first, keeping depth edges and masked pixels apart (0 = off, at most "
                    "7; 2 suits dithered or defocused binary fringes)")
        ->check(CLI::Range(0, CoordinateFilterOptions::kMaxRadius))
        ->capture_default_str();
    cmd->add_option("--smooth-tolerance", args->smooth.tolerance_px,
                    "with --smooth: neighbours further than this from the local plane (projector "
                    "px) are left out; 0 = 5 times the noise estimated from the scan")
        ->check(CLI::Range(0.0, 10000.0))
        ->capture_default_str();
    add_threads_option(*cmd, args->decode.threads);
    cmd->add_flag("--accept-inconsistent", args->accept_inconsistent,
                  "write the cloud (with a warning) even when the decoded field is "
                  "inconsistent with itself, or fits the calibration only mirrored along x "
                  "(every shift reversed, a projector in rear or ceiling mode), which otherwise "
                  "exits 5 naming the capture's field to check");
    cmd->add_flag("--correct-phase-error", args->decode.correct_phase_error,
                  "remove, from the capture alone, the periodic phase error a non-linear "
                  "projector response leaves, before reconstructing (for captures whose "
                  "response was never measured)");
    return action;
}

} // namespace fpp::calib
