// fpp-calib calibrate SESSION --out calib.yaml --table table.fpt
//                             [--stereo-report DIR] [--hybrid-report DIR]
//                             [--model rational|ray|polynomial]
//                             [--samples boards+model|boards|model] [--min-poses N]
//
// `stereo` and then `hybrid` on one checkerboard session, with their
// defaults, reading and searching every pose once: the table's view of each
// board (its corners, lit fraction and the column on its bright parts) is
// kept while the stereo calibration reads the poses. Writes what the two
// commands write, byte for byte, and, when the session holds a response ramp
// (response/), the projector's response as `response` would.

#include "calibration_outputs.hpp"
#include "cli_util.hpp"
#include "commands.hpp"
#include "response_fit.hpp"

#include "fpp/calib/hybrid_calibrate.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/stereo_session.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/fnv1a.hpp"
#include "fpp/yaml_fields.hpp"

#include <iostream>
#include <memory>
#include <optional>

namespace fpp::calib {

namespace {
struct CalibrateArgs {
    std::string session;
    std::string out;
    std::string table;
    std::string stereo_report;
    std::string hybrid_report;
    std::string response;
    std::string model = "rational";
    std::string samples = "boards+model";
    int min_poses = 6;
    int threads = 0;
};

int run_calibrate(const CalibrateArgs& args) {
    const std::filesystem::path out = args.out, table = args.table;
    check_output_file(out, "--out names the calibration file to write");
    check_output_file(table, "--table names the table file to write");
    check_report_folder(args.stereo_report, "calibration");
    check_report_folder(args.hybrid_report, "hybrid calibration");
    // The ramp first: a bad one stops the command before the long work.
    const std::filesystem::path ramp = std::filesystem::path(args.session) / kSessionResponseFolder;
    std::optional<ProjectorResponse> response;
    const std::filesystem::path response_file = args.response.empty()
                                                    ? out.parent_path() / kProjectorResponseFile
                                                    : std::filesystem::path(args.response);
    if (std::filesystem::is_directory(ramp)) {
        check_output_file(response_file, "--response names the response file to write");
        std::cerr << "== projector response\n";
        response = fit_and_report_response(ramp, std::cerr);
    }

    HybridOptions hybrid;
    hybrid.model = parse_table_model(args.model);
    hybrid.min_poses = args.min_poses;
    hybrid.samples = parse_hybrid_samples(args.samples);
    hybrid.threads = args.threads;
    hybrid.decode.threads = args.threads;
    hybrid.sv.threads = args.threads;
    hybrid.progress = [](const std::string& line) { std::cerr << line << "\n"; };
    hybrid.validate();

    StereoSessionOptions stereo;
    stereo.decode = hybrid.decode;
    stereo.progress = hybrid.progress;
    stereo.compare_corner_methods = !args.stereo_report.empty();
    stereo.stereo.suggest_next_poses = 1; // the report's advice
    std::vector<BoardView> views;
    keep_board_views(args.session, hybrid, stereo, views);
    std::cerr << "== stereo calibration\n";
    const SessionResult session = calibrate_session(args.session, stereo);
    write_stereo_outputs(session, out, args.stereo_report, nullptr);

    std::cerr << "== hybrid table, from the same poses\n";
    const StereoCalibration calibration = load_calibration(out);
    const std::string calib_bytes = yaml_fields::read_text_file(out);
    const std::vector<HybridResult> results =
        calibrate_hybrid(args.session, calibration, fnv1a64(calib_bytes.data(), calib_bytes.size()),
                         hybrid, {hybrid.model}, views);
    write_hybrid_outputs(results.front(), table, args.hybrid_report);
    if (response) {
        save_projector_response(response_file, *response);
        std::cout << "wrote " << response_file.string()
                  << " (the projector's response, for the board file's projector_response)\n";
    }
    return 0;
}
} // namespace

Action add_calibrate_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<CalibrateArgs>(
        app, "calibrate",
        "Calibrate a scanner from one checkerboard session: `stereo` (camera first, correction "
        "grids) and then `hybrid` (boards placed by the camera), each with its defaults, reading "
        "and searching every pose once. Writes the calibration file and the table, the same as "
        "the two commands would, and the projector's response (as `response`) when the "
        "session holds a response ramp",
        run_calibrate);
    cmd->add_option("session", args->session, "session folder (board.yaml kind checkerboard)")
        ->required();
    cmd->add_option("--out", args->out, "calibration file to write (YAML)")->required();
    cmd->add_option("--table", args->table, "table file to write (.fpt)")->required();
    cmd->add_option("--stereo-report", args->stereo_report,
                    "the stereo calibration's report folder (as `stereo --report`)");
    cmd->add_option("--hybrid-report", args->hybrid_report,
                    "the table's report folder (as `hybrid --report`)");
    cmd->add_option("--response", args->response,
                    "where to write the projector's response when the session holds a response "
                    "ramp (response/; default: projector-response.yaml beside --out)");
    cmd->add_option("--model", args->model, "table model (as `hybrid --model`)")
        ->capture_default_str()
        ->check(CLI::IsMember({"rational", "ray", "polynomial"}));
    cmd->add_option("--samples", args->samples,
                    "what the table is fitted to (as `hybrid --samples`)")
        ->capture_default_str()
        ->check(CLI::IsMember({"boards+model", "boards", "model"}));
    cmd->add_option("--min-poses", args->min_poses, "poses a pixel needs for a model (at least 4)")
        ->capture_default_str()
        ->check(CLI::Range(4, 1000));
    add_threads_option(*cmd, args->threads);
    return action;
}

} // namespace fpp::calib
