// Whole simulated captures: every frame of a sequence plus ground truth.

#include "fpp/patterns.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/yaml_fields.hpp"

#include <cstdio>
#include <string>

namespace fpp::sim {

namespace {

std::string frame_name(int index, int count) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%0*d.png", count > 1000 ? 4 : 3, index);
    return buf;
}

} // namespace

SimulatedCapture simulate(const Renderer& renderer, const Sequence& sequence, std::uint64_t seed) {
    const Rig& rig = renderer.rig();
    SimulatedCapture capture;
    CaptureManifest& m = capture.manifest;
    m.camera = rig.camera_size;
    m.projector = rig.projector_size;
    m.sequence = sequence;
    const std::vector<Image<std::uint8_t>> patterns = render_sequence(sequence, rig.projector_size);
    const int count = static_cast<int>(patterns.size());
    capture.frames.reserve(patterns.size());
    for (int k = 0; k < count; ++k) {
        m.frames.push_back(frame_name(k, count));
        capture.frames.push_back(
            renderer.render(patterns[static_cast<std::size_t>(k)], Renderer::frame_seed(seed, k)));
    }
    m.truth = TruthFiles{"truth_xyz.tiff", "truth_proj.tiff"};
    m.metadata_yaml = "source: fpp-sim\nrig: " + yaml_fields::format_string(rig.name) +
                      "\nbit_depth: " + std::to_string(rig.sensor.bit_depth) +
                      "\nseed: " + std::to_string(seed) + "\n";
    capture.truth_xyz = renderer.truth_xyz();
    capture.truth_projector = renderer.truth_projector();
    return capture;
}

SimulatedCapture simulate(const Rig& rig, const Scene& scene, const Sequence& sequence,
                          std::uint64_t seed) {
    const Renderer renderer(rig, scene);
    return simulate(renderer, sequence, seed);
}

void write_simulated_capture(const std::filesystem::path& folder, const SimulatedCapture& capture) {
    // The capture-set writer puts frames, truth TIFFs and capture.yaml into a
    // temporary sibling folder and renames it onto `folder` when complete.
    write_capture_set(folder, capture.manifest, capture.frames,
                      TruthImages{&capture.truth_xyz, &capture.truth_projector});
}

} // namespace fpp::sim
