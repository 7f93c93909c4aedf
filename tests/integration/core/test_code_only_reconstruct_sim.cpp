// A capture that codes the projector column with a code alone (no phase):
// white, black and 10 Gray planes along x, as SLStudio's Gray codec and the
// `plain` code-only sets of other tools. The decoder gives each pixel its
// code step's centre, so the floor of the coordinate's error is the
// quantisation: the true coordinate's projector column (pixel centres on
// integers) moved to the centre of the step that column belongs to. Both
// go through the same table (the rig's true geometry, rig_truth_table.hpp),
// and the decoded cloud is judged against the truth by that floor's error
// against the truth (target: at most 1.2 times it), with at least 95 % of
// the lit pixels decoded.
//
// Rig: the paper rig (ideal 8-bit camera at full resolution, 1600 x 1200:
// about 0.8 projector columns per camera pixel, so that the 1.25-column
// steps are resolved); the same with the effects rig's blur, noise and
// ambient light (paper-rig-effects.yaml). Scene: a tilted plane filling the
// field.

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"
#include "fpp/table_kernel.hpp"

#include "pattern_blocks.hpp"
#include "rig_truth_table.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

namespace {

using fpp::Image;

constexpr int kBits = 10;

// White, black and kBits Gray planes along x, the step the projector's
// width over 2^kBits (1280 / 1024 = 1.25 columns).
fpp::Sequence gray_only(fpp::Size projector) {
    return {fpp::WhiteBlock{}, fpp::BlackBlock{},
            fpp::test::gray(fpp::Axis::x, projector.width / double(1 << kBits), kBits, false)};
}

// The decoder's coordinate for the code step that projector column `c`
// belongs to: step n covers columns ceil(n P) .. ceil((n + 1) P) - 1, and
// its coordinate is their mean (fpp/decoder.hpp, code-only axes).
double step_centre(double column, double step) {
    const double n = std::floor(column / step);
    return 0.5 * (std::ceil(n * step) + std::ceil((n + 1) * step)) - 0.5;
}

struct Figures {
    std::size_t lit = 0, decoded = 0, compared = 0;
    double rms_z = 0;        // decoded, against the truth (mm)
    double rms_z_floor = 0;  // quantised truth, against the truth (mm)
    double rms_px = 0;       // decoded coordinate against the true one (projector px)
    double rms_px_floor = 0; // quantised truth against the truth (projector px)
};

Figures run(const fpp::sim::Rig& rig) {
    fpp::sim::Scene scene;
    scene.add(std::make_unique<fpp::sim::Plane>(
        fpp::sim::Pose::from_euler_deg({0.0, 0.0, 470.0}, 0.0, 15.0, 0.0), 600.0, 500.0, 0.8));
    const fpp::Sequence sequence = gray_only(rig.projector_size);
    const double step = std::get<fpp::GrayBlock>(sequence.back()).period;
    const fpp::sim::SimulatedCapture sim = fpp::sim::simulate(rig, scene, sequence);
    const fpp::DecodeResult decoded = fpp::decode(fpp::CaptureSet{{}, sim.manifest, sim.frames});
    EXPECT_EQ(decoded.method_x, "gray-code");

    Image<float> quantised(sim.truth_projector.width(), sim.truth_projector.height(), 1,
                           std::nanf(""));
    for (std::size_t i = 0; i < quantised.pixel_count(); ++i) {
        const float u = sim.truth_projector.data()[2 * i];
        if (std::isfinite(u))
            quantised.data()[i] = float(step_centre(std::round(double(u)), step));
    }
    const fpp::CoefficientTable table = fpp::test::rig_truth_table(rig);
    fpp::PointCloud cloud, floor_cloud;
    fpp::apply_table(table, decoded.proj_x, cloud);
    fpp::apply_table(table, quantised, floor_cloud);

    Figures f;
    double sum_z = 0, sum_floor = 0, sum_px = 0, sum_px_floor = 0;
    for (std::size_t i = 0; i < quantised.pixel_count(); ++i) {
        const double u = sim.truth_projector.data()[2 * i];
        const double z_true = sim.truth_xyz.data()[3 * i + 2];
        if (!std::isfinite(u) || !std::isfinite(z_true))
            continue;
        ++f.lit;
        if (!(decoded.mask.data()[i] & fpp::kDecodeValid))
            continue;
        ++f.decoded;
        const double z = cloud.xyz.data()[3 * i + 2];
        const double z_floor = floor_cloud.xyz.data()[3 * i + 2];
        if (!std::isfinite(z) || !std::isfinite(z_floor))
            continue;
        ++f.compared;
        sum_z += (z - z_true) * (z - z_true);
        sum_floor += (z_floor - z_true) * (z_floor - z_true);
        const double du = double(decoded.proj_x.data()[i]) - u;
        sum_px += du * du;
        const double dq = double(quantised.data()[i]) - u;
        sum_px_floor += dq * dq;
    }
    const auto n = double(std::max<std::size_t>(f.compared, 1));
    f.rms_z = std::sqrt(sum_z / n);
    f.rms_z_floor = std::sqrt(sum_floor / n);
    f.rms_px = std::sqrt(sum_px / n);
    f.rms_px_floor = std::sqrt(sum_px_floor / n);
    std::printf("[ figures  ] %s: lit %zu, decoded %.2f %%, compared %zu; coordinate RMS %.3f px "
                "(quantisation floor %.3f; step %.3f px, step / sqrt(12) %.3f); Z RMS %.4f mm, "
                "quantisation floor %.4f mm (ratio %.3f)\n",
                rig.name.c_str(), f.lit, 100.0 * double(f.decoded) / double(f.lit), f.compared,
                f.rms_px, f.rms_px_floor, step, step / std::sqrt(12.0), f.rms_z, f.rms_z_floor,
                f.rms_z / f.rms_z_floor);
    return f;
}

TEST(CodeOnlyReconstructSim, GrayPlanesAloneReachTheirQuantisationFloor) {
    const Figures f = run(fpp::sim::Rig::paper());
    ASSERT_GT(f.lit, 1000000u);
    EXPECT_GE(double(f.decoded), 0.95 * double(f.lit));
    EXPECT_LE(f.rms_z, 1.2 * f.rms_z_floor);
    // The same in the coordinate itself, before any table.
    EXPECT_LE(f.rms_px, 1.2 * f.rms_px_floor);
}

TEST(CodeOnlyReconstructSim, GrayPlanesAloneWithBlurNoiseAndAmbientLight) {
    const Figures f = run(fpp::sim::load_rig(fpp::sim::effects_rig_path()));
    EXPECT_GE(double(f.decoded), 0.95 * double(f.lit));
    EXPECT_LE(f.rms_z, 1.2 * f.rms_z_floor);
}

} // namespace
