// fpp-calib stereo SESSION --out calib.yaml [--report DIR] [--drop-outliers]
//                          [--corner-method poly|bilinear|homography] [--no-skew]
//                          [--compare-skew] [--procedure camera-first|joint]
//                          [--camera-grid CxR] [--projector-grid CxR]

#include "calibration_outputs.hpp"
#include "cli_util.hpp"
#include "commands.hpp"

#include "fpp/calib/held_out_check.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/stereo_session.hpp"
#include "fpp/error.hpp"

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

namespace fpp::calib {

namespace {
struct StereoArgs {
    std::string session;
    std::string out;
    std::string report;
    std::string corner_method = "poly";
    bool drop_outliers = false;
    bool no_skew = false;
    bool compare_skew = false;
    bool held_out = false;
    std::string procedure = "camera-first";
    std::string camera_grid = "12x9";
    std::string projector_grid = "12x8";
    int threads = 0;
};

// "CxR" control points, or "0x0" (or "none") for no grid.
GridSize parse_grid(const std::string& text, const char* option) {
    if (text == "none")
        return {};
    int columns = -1, rows = -1;
    char x = 0, extra = 0;
    if (std::sscanf(text.c_str(), "%d%c%d%c", &columns, &x, &rows, &extra) != 3 || x != 'x' ||
        columns < 0 || rows < 0)
        throw std::invalid_argument(std::string(option) +
                                    ": expected COLUMNSxROWS, e.g. 12x9, "
                                    "or none; got '" +
                                    text + "'");
    return {columns, rows};
}

int run_stereo(const StereoArgs& args) {
    // Output locations are checked before the work, so that bad arguments
    // cost nothing and nothing is written on failure.
    const std::filesystem::path out = args.out;
    check_output_file(out, "--out names the calibration file to write");
    check_report_folder(args.report, "calibration");

    StereoSessionOptions options;
    options.corners.method = corner_method_from_string(args.corner_method);
    options.stereo.skew = !args.no_skew;
    options.compare_skew = args.compare_skew;
    options.compare_corner_methods = !args.report.empty();
    options.stereo.drop_outliers = args.drop_outliers;
    options.stereo.procedure = parse_stereo_procedure(args.procedure);
    options.stereo.camera_grid = parse_grid(args.camera_grid, "--camera-grid");
    options.stereo.projector_grid = parse_grid(args.projector_grid, "--projector-grid");
    options.stereo.suggest_next_poses = 1; // the report's advice
    options.stereo.validate();
    options.decode.threads = args.threads;
    options.progress = [](const std::string& line) { std::cerr << line << "\n"; };
    const SessionResult result = calibrate_session(args.session, options);

    const StereoResult& s = result.stereo;
    for (const PoseResidual& p : s.calibration.poses)
        if (!p.note.empty())
            std::cerr << "pose " << p.name << ": " << p.note
                      << (p.used ? " (kept; --drop-outliers drops it)" : "") << "\n";
    std::optional<HeldOutCheck> held_out;
    if (args.held_out) {
        std::cerr << "held-out check: calibrating " << result.calibrated.size()
                  << " times, each without one pose\n";
        held_out = check_held_out(result, options);
        std::cout << held_out->summary();
    }
    write_stereo_outputs(result, out, args.report, held_out ? &*held_out : nullptr);
    return 0;
}
} // namespace

Action add_stereo_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<StereoArgs>(
        app, "stereo",
        "Stereo-calibrate camera and projector from a session folder (board.yaml with kind "
        "checkerboard and one capture set per pose, phase in x and y): corners on the white frame "
        "(or the phase frames), their projector coordinates from the absolute phase, then a "
        "bundle adjustment with skew and dense correction grids: by default the camera alone from "
        "its corners (so the boards are placed by the camera), then the projector from the "
        "corners and dense samples of the boards' white parts",
        run_stereo);
    cmd->add_option("session", args->session, "session folder")->required();
    cmd->add_option("--out", args->out, "calibration file to write (YAML)")->required();
    cmd->add_option(
        "--report", args->report,
        "report folder: summary.md and PNG figures (replaced if it holds an earlier report)");
    cmd->add_option("--corner-method", args->corner_method,
                    "projector coordinates of the corners: poly (the paper's local polynomial on "
                    "the white squares), bilinear, homography (Moreno-Taubin)")
        ->capture_default_str()
        ->check(CLI::IsMember({"poly", "bilinear", "homography"}));
    cmd->add_flag("--drop-outliers", args->drop_outliers,
                  "drop poses whose RMS exceeds 2.5 x the median pose RMS and refine again");
    cmd->add_flag("--no-skew", args->no_skew,
                  "fix skew at 0 for both devices (estimated by default)");
    cmd->add_flag("--compare-skew", args->compare_skew,
                  "also calibrate with the other skew setting and compare the two in the report");
    cmd->add_flag("--held-out", args->held_out,
                  "also measure the calibration's absolute accuracy on poses it did not see: "
                  "each pose left out in turn, the pair calibrated from the others, the "
                  "left-out board's corners measured and compared with the board (3D fit RMS, "
                  "scale error, corner-to-corner length errors)");
    cmd->add_option("--procedure", args->procedure,
                    "camera-first: the camera from its corners alone, then the projector with the "
                    "boards held; joint: the paper's, both devices and the boards together "
                    "(a projector lens defect then moves the camera and the boards)")
        ->capture_default_str()
        ->check(CLI::IsMember({"camera-first", "joint"}));
    cmd->add_option("--camera-grid", args->camera_grid,
                    "control points (COLUMNSxROWS) of the camera's correction grid, a smooth "
                    "displacement field over the image for lens defects the lens model lacks; "
                    "none for no grid")
        ->capture_default_str();
    cmd->add_option("--projector-grid", args->projector_grid, "the same for the projector")
        ->capture_default_str();
    add_threads_option(*cmd, args->threads);
    return action;
}

} // namespace fpp::calib
