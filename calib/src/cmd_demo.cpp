// fpp-calib demo --out DIR: the main job on the virtual scanner. Simulates a
// scan of the default scene on the paper's rig, decodes it, and reports the
// decoding error against ground truth.

#include "cli_util.hpp"
#include "commands.hpp"
#include "decode_outputs.hpp"
#include "simulated_rig_options.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <iostream>
#include <memory>
#include <sstream>

namespace fpp::calib {

namespace {
constexpr const char* kDemoMarker = ".fpp-demo";

struct DemoArgs {
    std::string out = "demo-out";
    std::string rig = sim::effects_rig_path().string();
    std::string scene = "composite";
    std::string sequence = "gray-xy";
    std::uint64_t seed = 1;
};

// The demo owns its output folder; it refuses to reuse a folder it did not make.
void prepare_output(const std::filesystem::path& out) {
    if (std::filesystem::exists(out)) {
        if (!std::filesystem::exists(out / kDemoMarker))
            throw std::runtime_error(out.string() +
                                     ": exists and was not made by `fpp-calib demo`; "
                                     "choose another --out");
        std::filesystem::remove_all(out / "capture");
        std::filesystem::remove_all(out / "decoded");
    }
    std::filesystem::create_directories(out);
    write_file_atomically(out / kDemoMarker, "made by fpp-calib demo\n");
}

int run_demo(const DemoArgs& args) {
    const std::filesystem::path out = args.out;
    const sim::Rig rig = sim::load_rig(args.rig);
    const sim::Scene scene = sim::scene_from_argument(args.scene);
    const Sequence sequence = sequence_from_argument(args.sequence, rig.projector_size);
    prepare_output(out);

    std::cerr << "[1/3] simulating " << frame_count(sequence) << " frames of scene '" << args.scene
              << "' on rig '" << rig.name << "'\n";
    Stopwatch sim_watch;
    const sim::SimulatedCapture simulated = sim::simulate(rig, scene, sequence, args.seed);
    sim::write_simulated_capture(out / "capture", simulated);
    const double sim_seconds = sim_watch.seconds();

    std::cerr << "[2/3] decoding\n";
    const CaptureSet capture = read_capture_set(out / "capture");
    Stopwatch decode_watch;
    const DecodeResult result = decode(capture);
    const double decode_seconds = decode_watch.seconds();

    std::cerr << "[3/3] writing maps and report\n";
    write_decode_images(out / "decoded", result, capture.manifest);
    std::ostringstream report;
    report << "# fpp demo: a simulated scan, decoded\n\n"
           << "- rig: `" << args.rig << "` (" << rig.name << ")\n"
           << "- scene: " << args.scene << "\n"
           << "- sequence: " << args.sequence << " (" << frame_count(sequence) << " frames)\n"
           << "- simulation: " << sim_seconds << " s; capture set in `capture/`\n"
           << "- decoded maps in `decoded/` (proj_x.tiff, proj_y.tiff, modulation.tiff, "
              "mask.png, false-colour PNGs)\n\n";
    report << decode_summary(result, capture, decode_seconds);
    write_file_atomically(out / "report.md", report.str());
    std::cout << report.str() << "\nreport: " << (out / "report.md").string() << "\n";
    return 0;
}
} // namespace

Action add_demo_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<DemoArgs>(
        app, "demo",
        "Main job on the virtual scanner: simulate a scan, decode it, report the "
        "error against ground truth",
        run_demo);
    cmd->add_option("--out", args->out, "output folder")->capture_default_str();
    cmd->add_option("--rig", args->rig, "rig YAML file")
        ->capture_default_str()
        ->check(CLI::ExistingFile);
    cmd->add_option("--scene", args->scene, "scene name or YAML file")->capture_default_str();
    cmd->add_option("--sequence", args->sequence, "sequence name or YAML file")
        ->capture_default_str();
    cmd->add_option("--seed", args->seed, "noise seed")->capture_default_str();
    return action;
}

} // namespace fpp::calib
