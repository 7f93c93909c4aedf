#pragma once
// Renders camera frames of a scene lit by projector patterns, with ground
// truth. Geometry (ray casting through the distorted camera model, projector
// coordinates through the distorted projector model, shadows) is computed once
// per pose and reused for every frame.
//
// Radiometry of a camera pixel seeing surface point P (DN at the sensor's bit depth):
//   white_level * (albedo + s) * cos(incidence from the projector) * falloff
//     * (projector light at P) + ambient * (albedo + ks),
// s = SpecularLobe::relative_reflectance(n.h) of the object's lobe (0 without
// one; point-sampled at the pixel centre: the footprint is not averaged),
// ks its strength (uniform ambient light reflected by the lobe),
// projector light = bilinear sample, at P's projector coordinate, of the
// projector image mapped through (level/255)^gamma + black_level and blurred
// by the projector defocus. Points in projector shadow, facing away from the
// projector or outside its image get ambient only. Then camera defocus blur,
// shot noise (Gaussian approximation of Poisson in electrons) and read
// noise, rounding and clipping to [0, 2^bit_depth - 1] (saturation), and
// MSB alignment into 16-bit frames for bit depths above 8.

#include "fpp/capture_set.hpp"
#include "fpp/image.hpp"
#include "fpp/parallel.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace fpp::sim {

class Renderer {
public:
    // `threads`: workers for ray casting and rendering (rows are split among
    // them); 0 = the machine's cores. Results do not depend on it. Copies of a
    // renderer share its workers.
    Renderer(const Rig& rig, const Scene& scene, int threads = 0);

    // 3 channels: camera-frame X, Y, Z in mm per camera pixel centre, NaN where no surface.
    const Image<float>& truth_xyz() const { return truth_xyz_; }
    // 2 channels: projector (x, y) lighting the point seen by each pixel centre,
    // NaN where no surface, in projector shadow or outside the projector image.
    const Image<float>& truth_projector() const { return truth_projector_; }
    // 1 channel: the scene object (Scene index, Hit::object) seen by each
    // pixel centre, lit or not; kNoObject where no surface.
    const Image<std::int32_t>& truth_object() const { return truth_object_; }
    static constexpr std::int32_t kNoObject = -1;
    // Scene::object_name of `object`, "none" for kNoObject. Throws
    // std::out_of_range for any other index outside the scene.
    const std::string& object_name(std::int32_t object) const;
    // Number of scene objects (indices 0 .. object_count() - 1).
    std::size_t object_count() const { return object_names_.size(); }

    // One camera frame of the scene lit by `projector_image` (8-bit drive
    // levels at projector resolution). Noise is seeded by `noise_seed` so
    // that renders are reproducible. `exposure_scale`: the exposure over the
    // rig's nominal one (the signal, and so its shot noise, scales with it;
    // read noise does not).
    // Throws std::invalid_argument if the image is not projector-sized, 1 channel.
    Frame render(const Image<std::uint8_t>& projector_image, std::uint64_t noise_seed,
                 double exposure_scale = 1.0) const;
    // The noise-free, unquantised camera image (DN, after camera defocus).
    Image<float> render_radiance(const Image<std::uint8_t>& projector_image) const;

    const Rig& rig() const { return rig_; }
    int threads() const { return pool_->size(); }
    // Replaces the workers (not while another thread renders with this renderer).
    void set_threads(int threads);
    // Albedo seen by each camera pixel (area-averaged on printed surfaces), 0 where no surface.
    const Image<float>& albedo() const { return albedo_; }
    // Noise seed of frame `frame` of a capture seeded with `seed`.
    static std::uint64_t frame_seed(std::uint64_t seed, int frame);

private:
    // Radiance (DN, camera size) into `radiance`; `light` and `blur` are scratch.
    void radiance_into(const Image<std::uint8_t>& projector_image, std::vector<float>& radiance,
                       std::vector<float>& light, std::vector<float>& blur) const;

    Rig rig_;
    // Shared so that the renderer stays copyable (copies share the workers).
    // A pool runs one parallel loop at a time: renders from several threads
    // take turns in their parallel parts.
    std::shared_ptr<ThreadPool> pool_;
    Image<float> truth_xyz_;
    Image<float> truth_projector_;
    Image<std::int32_t> truth_object_;
    std::vector<std::string> object_names_;
    Image<float>
        radiance_gain_; // DN per unit projector light (reflectance, shading, falloff); 0 if unlit
    Image<float> ambient_; // DN of ambient light
    Image<float> albedo_;
    // Bilinear sample of the projector light per camera pixel: top-left
    // projector sample index and fractional weights (0 for unlit pixels,
    // whose gain is 0, so that the render loop has no branch).
    std::vector<std::uint32_t> sample_index_;
    std::vector<float> sample_fx_;
    std::vector<float> sample_fy_;
};

struct SimulatedCapture {
    CaptureManifest manifest;
    std::vector<Frame> frames;
    Image<float> truth_xyz;
    Image<float> truth_projector;
};

// Renders every frame of `sequence` (patterns from fpp::render_sequence, no
// gamma precompensation). Frame k uses noise seed Renderer::frame_seed(seed, k).
// Frames are named 000.png, 001.png, ...; truth files truth_xyz.tiff and
// truth_proj.tiff; metadata records the rig name and the seed.
SimulatedCapture simulate(const Rig& rig, const Scene& scene, const Sequence& sequence,
                          std::uint64_t seed = 1);
SimulatedCapture simulate(const Renderer& renderer, const Sequence& sequence,
                          std::uint64_t seed = 1);
// Writes frames, truth TIFFs and capture.yaml (with its `truth` entry)
// atomically into `folder`, which must not exist.
void write_simulated_capture(const std::filesystem::path& folder, const SimulatedCapture& capture);

} // namespace fpp::sim
