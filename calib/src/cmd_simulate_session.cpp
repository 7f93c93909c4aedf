// fpp-calib simulate-session --kind checkerboard|plane --poses N --out DIR

#include "cli_util.hpp"
#include "commands.hpp"

#include "fpp/sim/rig.hpp"
#include "fpp/sim/session.hpp"

#include <iostream>
#include <memory>

namespace fpp::calib {

namespace {
struct SimulateSessionArgs {
    std::string kind = "checkerboard";
    int poses = 30;
    std::string out;
    std::string rig = sim::effects_rig_path().string();
    std::string sequence = "gray-xy";
    std::uint64_t seed = 1;
    int binning = 1;
    double read_noise = -1;
    bool no_effects = false;
};

int run_simulate_session(const SimulateSessionArgs& args) {
    if (std::filesystem::exists(args.out))
        throw std::runtime_error(args.out + ": already exists; a session is never overwritten");
    sim::Rig rig = sim::load_rig(args.rig);
    if (args.no_effects)
        rig = rig.without_effects();
    if (args.read_noise >= 0)
        rig.sensor.read_noise_dn = args.read_noise;
    if (args.binning > 1)
        rig = rig.binned_camera(args.binning);
    const Sequence sequence = sequence_from_argument(args.sequence, rig.projector_size);
    sim::SessionOptions options;
    options.kind = args.kind == "plane" ? sim::SessionKind::plane : sim::SessionKind::checkerboard;
    options.poses = args.poses;
    options.seed = args.seed;
    std::cerr << "simulating a " << args.kind << " session: " << args.poses << " poses of "
              << frame_count(sequence) << " frames on rig '" << rig.name << "' (camera "
              << rig.camera_size.width << " x " << rig.camera_size.height << ")\n";
    Stopwatch watch;
    sim::write_session(args.out, rig, sequence, options, [&](int done, int total) {
        std::cerr << "  pose " << done << "/" << total << " written ("
                  << static_cast<int>(watch.seconds()) << " s)\n";
    });
    std::cout << "wrote " << args.out << " (" << args.poses << " poses, " << watch.seconds()
              << " s)\n";
    return 0;
}
} // namespace

Action add_simulate_session_command(CLI::App& app) {
    auto args = std::make_shared<SimulateSessionArgs>();
    auto* cmd = app.add_subcommand(
        "simulate-session",
        "Render a calibration session on the virtual scanner: board.yaml and one capture set per "
        "board pose (pose-01, ...), poses spread through the calibration volume (400-560 mm, tilts "
        "up to ~28 deg), each fully visible to camera and projector. Checkerboard: 11 x 8 inner "
        "corners of 15 mm in the middle of a 420 x 375 mm white board (one session for the "
        "stereo calibration and the hybrid table); plane: a white board filling the field (the "
        "paper's hybrid session)");
    cmd->add_option("--kind", args->kind,
                    "checkerboard (stereo calibration and hybrid table) or plane (the paper's "
                    "hybrid session)")
        ->capture_default_str()
        ->check(CLI::IsMember({"checkerboard", "plane"}));
    cmd->add_option("--poses", args->poses, "number of board poses")
        ->capture_default_str()
        ->check(CLI::Range(1, 999));
    cmd->add_option("--out", args->out, "session folder to create (must not exist)")->required();
    cmd->add_option("--rig", args->rig, "rig YAML file (default: the paper rig with effects)")
        ->capture_default_str()
        ->check(CLI::ExistingFile);
    cmd->add_option("--sequence", args->sequence, "sequence name or YAML file with `sequence:`")
        ->capture_default_str();
    cmd->add_option("--seed", args->seed, "pose jitter and noise seed")->capture_default_str();
    cmd->add_option("--binning", args->binning,
                    "camera pixel binning factor (smaller, faster sessions)")
        ->capture_default_str()
        ->check(CLI::Range(1, 8));
    cmd->add_option("--read-noise", args->read_noise, "override the rig's read noise (DN)");
    cmd->add_flag("--no-effects", args->no_effects,
                  "switch off every effect outside the stereo model, and noise");
    return [args] { return run_simulate_session(*args); };
}

} // namespace fpp::calib
