// fpp-calib paper-experiments --out DIR [--binning B] [--seed S]
//     [--checkerboard-poses N] [--plane-poses N] [--board-poses N] [--timing-runs N]
//     [--threads N]
//     [--sv-calibration checkerboard|rig-model] [--rig RIG.yaml] [--keep-sessions]
//
// The paper's experiments on the virtual scanner in one run (see
// fpp/calib/paper_experiments.hpp): the paper's and our calibration
// procedures, then the inclined plane, the cylinder, a sphere, ball bars, the
// relief (with reconstruction times) and the N x N window timing, each
// against ground truth. DIR is
// written as a whole and must not exist. Progress on stderr; the targets and
// whether each is met on stdout.

#include "cli_util.hpp"
#include "commands.hpp"

#include "fpp/calib/paper_experiments.hpp"

#include <iostream>
#include <memory>

namespace fpp::calib {

namespace {
struct PaperArgs {
    std::string out;
    std::string rig;
    std::string sv_calibration = "checkerboard";
    PaperExperimentOptions options;
};

int run_paper(PaperArgs& args) {
    args.options.rig = args.rig;
    args.options.sv_calibration = parse_sv_calibration_source(args.sv_calibration);
    args.options.progress = [](const std::string& line) { std::cerr << line << "\n"; };
    const PaperExperimentResult result = run_paper_experiments(args.out, args.options);
    int met = 0;
    for (const PaperTarget& t : result.targets) {
        std::cout << (t.met ? "met     " : "NOT met ") << t.description << ": " << t.detail << "\n";
        met += t.met ? 1 : 0;
    }
    std::cout << met << " of " << result.targets.size() << " targets met; report in " << args.out
              << "/report/summary.md (" << static_cast<int>(result.seconds) << " s)\n";
    return 0;
}
} // namespace

Action add_paper_experiments_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<PaperArgs>(
        app, "paper-experiments",
        "Reproduce the paper's experiments on the virtual scanner and measure every calibration "
        "procedure against the truth: the paper's (a joint stereo calibration, hybrid tables "
        "from flat boards placed by SV, every model) and ours (one checkerboard session: "
        "camera-first stereo with correction grids, tables from boards placed by the camera); "
        "then the inclined plane, the 168 mm cylinder, a sphere, ball bars at seven places and "
        "the relief reconstructed by every method, with shape fits, errors against ground truth "
        "(with and without noise), reconstruction times and N x N window timing; writes the "
        "calibrations, table-<method>.fpt, reports, the scans and DIR/report",
        run_paper);
    cmd->add_option("--out", args->out, "folder to create (must not exist)")->required();
    cmd->add_option("--sv-calibration", args->sv_calibration,
                    "SV model: checkerboard (stereo calibration from a simulated session, the "
                    "paper's procedure) or rig-model (the rig's own 5-coefficient model: SV "
                    "without the distortion outside that model, no stereo calibration)")
        ->capture_default_str()
        ->check(CLI::IsMember({"checkerboard", "rig-model"}));
    cmd->add_option("--binning", args->options.binning,
                    "camera pixel binning (1 = the paper's 1600 x 1200)")
        ->capture_default_str()
        ->check(CLI::Range(1, 8));
    cmd->add_option("--seed", args->options.seed, "seed of poses and noise")->capture_default_str();
    cmd->add_option("--checkerboard-poses", args->options.checkerboard_poses,
                    "checkerboard poses of the stereo calibration (the paper's 15)")
        ->capture_default_str()
        ->check(CLI::Range(3, 200));
    cmd->add_option("--plane-poses", args->options.plane_poses,
                    "flat-board poses of the hybrid calibration (the paper's 30)")
        ->capture_default_str()
        ->check(CLI::Range(6, 500));
    cmd->add_option("--board-poses", args->options.board_poses,
                    "checkerboard poses of our session (stereo and hybrid calibration)")
        ->capture_default_str()
        ->check(CLI::Range(6, 500));
    cmd->add_option("--timing-runs", args->options.timing_runs,
                    "runs per timing (the best is kept)")
        ->capture_default_str()
        ->check(CLI::Range(1, 100));
    add_threads_option(*cmd, args->options.threads)
        ->description("worker threads for simulation, decoding and calibration (0 = all cores; "
                      "the timings use one)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--rig", args->rig,
                    "rig YAML file (default: board/sim/paper-rig-lens-defects.yaml)")
        ->check(CLI::ExistingFile);
    cmd->add_flag("--keep-sessions", args->options.keep_sessions,
                  "keep the calibration sessions in DIR/sessions (large at full size)");
    return action;
}

} // namespace fpp::calib
