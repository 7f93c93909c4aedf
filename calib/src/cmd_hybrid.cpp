// fpp-calib hybrid SESSION --calib calib.yaml --out table.fpt [--report DIR]
//                         [--model rational|ray|polynomial] [--min-poses N]
//                         [--samples boards+model|boards|model]

#include "calibration_outputs.hpp"
#include "cli_util.hpp"
#include "commands.hpp"

#include "fpp/calib/hybrid_calibrate.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/error.hpp"
#include "fpp/fnv1a.hpp"
#include "fpp/yaml_fields.hpp"

#include <iostream>
#include <memory>

namespace fpp::calib {

namespace {
struct HybridArgs {
    std::string session;
    std::string calib;
    std::string calib_format = "auto";
    std::string out;
    std::string report;
    std::string model = "rational";
    std::string samples = "boards+model";
    int min_poses = 6;
    int threads = 0;
};

int run_hybrid(const HybridArgs& args) {
    const std::filesystem::path out = args.out;
    check_output_file(out, "--out names the table file to write");
    check_report_folder(args.report, "hybrid calibration");
    const StereoCalibration calibration =
        load_calibration(args.calib, parse_calibration_format(args.calib_format));
    const std::string calib_bytes = yaml_fields::read_text_file(args.calib);

    HybridOptions options;
    options.model = parse_table_model(args.model);
    options.min_poses = args.min_poses;
    options.samples = parse_hybrid_samples(args.samples);
    options.threads = args.threads;
    options.decode.threads = args.threads;
    options.sv.threads = args.threads;
    options.progress = [](const std::string& line) { std::cerr << line << "\n"; };
    const HybridResult result = calibrate_hybrid(
        args.session, calibration, fnv1a64(calib_bytes.data(), calib_bytes.size()), options);
    write_hybrid_outputs(result, out, args.report);
    return 0;
}
} // namespace

Action add_hybrid_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<HybridArgs>(
        app, "hybrid",
        "Fit the hybrid model per camera pixel, from phase (projector column) to X, Y, Z, and "
        "write the coefficient table the scanner loads (.fpt). The session's board.yaml decides "
        "the procedure. kind checkerboard (one session of about 30 poses with fringes in x and y, "
        "the same as for `stereo`): each board is placed by the camera alone with --calib's "
        "camera model, the samples are where the pixels' rays meet it on its white parts, and "
        "the stereo model adds samples between the boards; kind plane (the paper's): flat "
        "white boards reconstructed by SV with --calib and corrected onto their best planes",
        run_hybrid);
    cmd->add_option("session", args->session, "session folder")->required();
    cmd->add_option("--calib", args->calib, "stereo calibration file")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--calib-format", args->calib_format,
                    "calibration format: auto, fpp, slstudio, slmaster")
        ->capture_default_str()
        ->check(CLI::IsMember({"auto", "fpp", "slstudio", "slmaster"}));
    cmd->add_option("--out", args->out, "table file to write (.fpt)")->required();
    cmd->add_option("--report", args->report,
                    "report folder: summary.md, fit RMS maps, pose counts, plane residuals "
                    "(replaced if it holds an earlier report)");
    cmd->add_option("--model", args->model,
                    "rational: points corrected along the camera ray, Z a cubic over (1 + d t), "
                    "X and Y from the ray (default); ray: the same with a cubic for Z; "
                    "polynomial: the paper's perpendicular correction, cubics for X, Y, Z")
        ->capture_default_str()
        ->check(CLI::IsMember({"rational", "ray", "polynomial"}));
    cmd->add_option("--samples", args->samples,
                    "checkerboard sessions: what the tables are fitted to: the boards' samples "
                    "and the stereo model's between them (boards+model), the boards' alone "
                    "(boards), or the stereo model's alone over the depths the boards reached "
                    "(model)")
        ->capture_default_str()
        ->check(CLI::IsMember({"boards+model", "boards", "model"}));
    cmd->add_option("--min-poses", args->min_poses, "poses a pixel needs for a model (at least 4)")
        ->capture_default_str()
        ->check(CLI::Range(4, 1000));
    add_threads_option(*cmd, args->threads);
    return action;
}

} // namespace fpp::calib
