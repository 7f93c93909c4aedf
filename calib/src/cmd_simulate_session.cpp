// fpp-calib simulate-session --kind checkerboard|plane --poses N --out DIR

#include "cli_util.hpp"
#include "commands.hpp"
#include "simulated_rig_options.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/projector_response.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/session.hpp"
#include "fpp/yaml_fields.hpp"

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
    double max_tilt_deg = sim::SessionOptions{}.max_tilt_deg;
};

// The projector's response ramp at the first pose, as the scanner records it
// (POST /api/v1/sessions/{name}/response): one frame per standard level,
// rendered through the rig's projector response, with noise seeds of their
// own (poses use seed * 1000003 + pose, pose < 999).
ResponseRamp simulate_response_ramp(const sim::Rig& rig, const sim::SessionOptions& options) {
    const sim::Pose first = sim::session_poses(rig, options).front();
    const sim::Renderer renderer(rig, sim::session_scene(options, first));
    const std::uint64_t seed = options.seed * 1000003ULL + 999;
    ResponseRamp ramp;
    ramp.levels = standard_ramp_levels();
    for (std::size_t k = 0; k < ramp.levels.size(); ++k)
        ramp.frames.push_back(
            renderer.render(ramp_pattern(ramp.levels[k], rig.projector_size),
                            sim::Renderer::frame_seed(seed, static_cast<int>(k))));
    // The rig's truth, so that `fpp-calib response` can report the fit's error.
    ramp.metadata_yaml =
        "simulated: true\nrig: " + yaml_fields::format_string(rig.name) +
        "\nprojector_gamma: " + yaml_fields::format_real(rig.projector_optics.gamma) +
        "\nprojector_black_level: " + yaml_fields::format_real(rig.projector_optics.black_level) +
        "\nsession_pose: 1\nseed: " + std::to_string(seed);
    return ramp;
}

int run_simulate_session(const SimulateSessionArgs& args) {
    if (std::filesystem::exists(args.out))
        throw std::runtime_error(args.out + ": already exists; a session is never overwritten");
    const sim::Rig rig = rig_from_options(args.rig, args.no_effects, args.read_noise, args.binning);
    const Sequence sequence = sequence_from_argument(args.sequence, rig.projector_size);
    sim::SessionOptions options;
    options.kind = args.kind == "plane" ? sim::SessionKind::plane : sim::SessionKind::checkerboard;
    options.poses = args.poses;
    options.seed = args.seed;
    options.max_tilt_deg = args.max_tilt_deg;
    std::cerr << "simulating a " << args.kind << " session: " << args.poses << " poses of "
              << frame_count(sequence) << " frames on rig '" << rig.name << "' (camera "
              << rig.camera_size.width << " x " << rig.camera_size.height << ")\n";
    Stopwatch watch;
    const ResponseRamp ramp = simulate_response_ramp(rig, options);
    // The poses and the ramp appear together or not at all: write_session
    // publishes its folder onto our temporary one, which is then published.
    write_folder_atomically(args.out, [&](const std::filesystem::path& temp) {
        std::filesystem::remove(temp);
        sim::write_session(temp, rig, sequence, options, [&](int done, int total) {
            std::cerr << "  pose " << done << "/" << total << " written ("
                      << static_cast<int>(watch.seconds()) << " s)\n";
        });
        write_response_ramp(temp / kSessionResponseFolder, ramp);
    });
    std::cerr << "  projector response ramp (" << ramp.levels.size()
              << " grey levels at the first pose) written to " << kSessionResponseFolder << "/\n";
    std::cout << "wrote " << args.out << " (" << args.poses << " poses, " << watch.seconds()
              << " s)\n";
    return 0;
}
} // namespace

Action add_simulate_session_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<SimulateSessionArgs>(
        app, "simulate-session",
        "Render a calibration session on the virtual scanner: board.yaml, one capture set per "
        "board pose (pose-01, ...) and the projector's response ramp at the first pose "
        "(response/), poses spread through the calibration volume (400-560 mm, tilts "
        "up to ~28 deg), each fully visible to camera and projector. Checkerboard: 11 x 8 inner "
        "corners of 15 mm in the middle of a 420 x 375 mm white board (one session for the "
        "stereo calibration and the hybrid table); plane: a white board filling the field (the "
        "paper's hybrid session)",
        run_simulate_session);
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
    // A hurried session (small tilts) leaves the depth scale poorly
    // determined: what `correct` with an artefact is for.
    cmd->add_option("--max-tilt-deg", args->max_tilt_deg,
                    "largest board tilt about its x and y axes (degrees)")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 40.0));
    cmd->add_flag("--no-effects", args->no_effects,
                  "switch off every effect outside the stereo model, and noise");
    return action;
}

} // namespace fpp::calib
