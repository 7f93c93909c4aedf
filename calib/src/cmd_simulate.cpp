// fpp-calib simulate --rig RIG --scene SCENE --sequence SEQ --out DIR

#include "cli_util.hpp"
#include "commands.hpp"
#include "simulated_rig_options.hpp"

#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <iostream>
#include <memory>

namespace fpp::calib {

namespace {
struct SimulateArgs {
    std::string rig = sim::default_rig_path().string();
    std::string scene = "composite";
    std::string sequence = "gray-xy";
    std::string out;
    std::uint64_t seed = 1;
    double read_noise = -1;
    bool no_effects = false;
    int binning = 1;
};

int run_simulate(const SimulateArgs& args) {
    if (std::filesystem::exists(args.out))
        throw std::runtime_error(args.out + ": already exists; a capture set is never overwritten");
    const sim::Rig rig = rig_from_options(args.rig, args.no_effects, args.read_noise, args.binning);
    const sim::Scene scene = sim::scene_from_argument(args.scene);
    const Sequence sequence = sequence_from_argument(args.sequence, rig.projector_size);
    std::cerr << "simulating " << frame_count(sequence) << " frames of scene '" << args.scene
              << "' on rig '" << rig.name << "'\n";
    Stopwatch watch;
    const sim::SimulatedCapture capture = sim::simulate(rig, scene, sequence, args.seed);
    sim::write_simulated_capture(args.out, capture);
    std::cout << "wrote " << args.out << " (" << capture.frames.size() << " frames, "
              << watch.seconds() << " s)\n";
    return 0;
}
} // namespace

Action add_simulate_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<SimulateArgs>(
        app, "simulate", "Render a capture set with ground truth on the virtual scanner",
        run_simulate);
    cmd->add_option("--rig", args->rig, "rig YAML file (board/sim/*.yaml)")
        ->capture_default_str()
        ->check(CLI::ExistingFile);
    cmd->add_option("--scene", args->scene, "scene name or scene YAML file")->capture_default_str();
    cmd->add_option("--sequence", args->sequence, "sequence name or YAML file with `sequence:`")
        ->capture_default_str();
    cmd->add_option("--out", args->out, "capture set folder to create (must not exist)")
        ->required();
    cmd->add_option("--seed", args->seed, "noise seed")->capture_default_str();
    cmd->add_option("--read-noise", args->read_noise, "override the rig's read noise (DN)");
    cmd->add_option("--binning", args->binning,
                    "camera pixel binning factor (as simulate-session --binning)")
        ->capture_default_str()
        ->check(CLI::Range(1, 8));
    cmd->add_flag("--no-effects", args->no_effects,
                  "switch off every effect outside the stereo model, and noise");
    return action;
}

} // namespace fpp::calib
