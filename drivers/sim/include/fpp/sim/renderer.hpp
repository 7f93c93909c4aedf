#pragma once
// Renders camera frames of a scene lit by projector patterns, with ground
// truth. Geometry (ray casting through the distorted camera model, projector
// coordinates through the distorted projector model, shadows) is computed once
// per pose and reused for every frame.

#include "fpp/capture_set.hpp"
#include "fpp/image.hpp"
#include "fpp/sim/rig.hpp"
#include "fpp/sim/scene.hpp"

#include <cstdint>
#include <filesystem>
#include <vector>

namespace fpp::sim {

class Renderer {
public:
    Renderer(const Rig& rig, const Scene& scene);

    // 3 channels: camera-frame X, Y, Z in mm per camera pixel centre, NaN where no surface.
    const Image<float>& truth_xyz() const { return truth_xyz_; }
    // 2 channels: projector (x, y) lighting the point seen by each pixel centre,
    // NaN where no surface, in projector shadow or outside the projector image.
    const Image<float>& truth_projector() const { return truth_projector_; }

    // One camera frame of the scene lit by `projector_image` (8-bit drive
    // levels at projector resolution). Noise is seeded by `noise_seed` so
    // that renders are reproducible.
    Frame render(const Image<std::uint8_t>& projector_image, std::uint64_t noise_seed) const;

    const Rig& rig() const { return rig_; }

private:
    Rig rig_;
    Image<float> truth_xyz_;
    Image<float> truth_projector_;
    Image<float> radiance_gain_; // DN per unit projector light (albedo, shading, falloff)
    Image<float> ambient_;       // DN of ambient light
};

struct SimulatedCapture {
    CaptureManifest manifest;
    std::vector<Frame> frames;
    Image<float> truth_xyz;
    Image<float> truth_projector;
};

// Renders every frame of `sequence`. Frame k uses noise seed (seed, k).
SimulatedCapture simulate(const Rig& rig, const Scene& scene, const Sequence& sequence,
                          std::uint64_t seed = 1);
// Writes frames, truth TIFFs and capture.yaml (with its `truth` entry)
// atomically into `folder`, which must not exist.
void write_simulated_capture(const std::filesystem::path& folder, const SimulatedCapture& capture);

} // namespace fpp::sim
