// SV reconstruction against the simulator's ground truth, with the exact
// stereo model of the rig (every effect off).
//
// Two levels:
//   - geometry alone: the renderer's true projector coordinates as the
//     "decoded" input, so any error is the reconstruction's own;
//   - the whole chain: simulated frames, decoded, reconstructed (x+y and x
//     only), noise-free and with 1 DN read noise.
// The camera is binned 4x (400 x 300, same field of view and distortion) to
// keep the suite fast under sanitizers.

#include "test_support.hpp"

#include "fpp/calib/simulated_rig.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/decoder.hpp"
#include "fpp/sequences.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace {

using fpp::calib::ReconstructAxes;
using fpp::calib::StereoCalibration;
using fpp::calib::SvOptions;
using fpp::calib::SvReconstructor;
using fpp::calib::SvStats;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

fpp::sim::Rig test_rig() {
    return fpp::sim::Rig::paper().without_effects().binned_camera(4);
}

// A decode result holding the true projector coordinates (NaN where none).
fpp::DecodeResult from_truth(const fpp::Image<float>& truth_projector) {
    fpp::DecodeResult d;
    d.camera = truth_projector.size();
    d.proj_x = fpp::Image<float>(d.camera, 1, kNaN);
    d.proj_y = fpp::Image<float>(d.camera, 1, kNaN);
    d.modulation = fpp::Image<float>(d.camera, 1, 100.0f);
    d.mean = fpp::Image<float>(d.camera, 1, 120.0f);
    d.mask = fpp::Image<std::uint8_t>(d.camera, 1, 0);
    for (std::size_t i = 0; i < truth_projector.pixel_count(); ++i) {
        const float x = truth_projector.data()[2 * i], y = truth_projector.data()[2 * i + 1];
        d.proj_x.data()[i] = x;
        d.proj_y.data()[i] = y;
        if (std::isfinite(x) && std::isfinite(y))
            d.mask.data()[i] = fpp::kDecodeValid;
    }
    return d;
}

// True where the truth surface is continuous over the 3x3 neighbourhood
// (depth steps under 1 mm): decoding blends the two sides of an occlusion
// edge within a pixel, which no reconstruction can undo.
std::vector<bool> smooth_pixels(const fpp::Image<float>& truth_xyz) {
    const int w = truth_xyz.width(), h = truth_xyz.height();
    std::vector<bool> smooth(truth_xyz.pixel_count(), false);
    for (int y = 1; y + 1 < h; ++y)
        for (int x = 1; x + 1 < w; ++x) {
            const float z = truth_xyz.at(x, y, 2);
            bool ok = std::isfinite(z);
            for (int dy = -1; dy <= 1 && ok; ++dy)
                for (int dx = -1; dx <= 1 && ok; ++dx) {
                    const float n = truth_xyz.at(x + dx, y + dy, 2);
                    ok = std::isfinite(n) && std::fabs(n - z) < 1.0f;
                }
            smooth[std::size_t(y) * std::size_t(w) + std::size_t(x)] = ok;
        }
    return smooth;
}

struct ErrorStats {
    std::size_t compared = 0; // pixels with a point and a true surface (and in `only`)
    std::size_t missing = 0;  // pixels in `only` lit by the projector but without a point
    double rms = 0;           // 3D distance, mm
    double max = 0;
    double rms_z = 0;
    double coverage() const {
        return compared + missing ? double(compared) / double(compared + missing) : 0.0;
    }
};

// `truth_projector` tells which pixels the projector lights (the others,
// in its shadow, cannot be decoded).
ErrorStats compare(const fpp::PointCloud& cloud, const fpp::Image<float>& truth,
                   const fpp::Image<float>& truth_projector,
                   const std::vector<bool>* only = nullptr) {
    ErrorStats s;
    double sum = 0, sum_z = 0;
    for (std::size_t i = 0; i < truth.pixel_count(); ++i) {
        if (only && !(*only)[i])
            continue;
        const float* t = truth.data() + 3 * i;
        const float* p = cloud.xyz.data() + 3 * i;
        if (!std::isfinite(t[2]))
            continue;
        if (!std::isfinite(p[2])) {
            if (std::isfinite(truth_projector.data()[2 * i]))
                ++s.missing;
            continue;
        }
        const double dx = double(p[0]) - double(t[0]), dy = double(p[1]) - double(t[1]),
                     dz = double(p[2]) - double(t[2]);
        const double d2 = dx * dx + dy * dy + dz * dz;
        sum += d2;
        sum_z += dz * dz;
        s.max = std::max(s.max, std::sqrt(d2));
        ++s.compared;
    }
    if (s.compared) {
        s.rms = std::sqrt(sum / double(s.compared));
        s.rms_z = std::sqrt(sum_z / double(s.compared));
    }
    return s;
}

// Least-squares plane n . p = d (|n| = 1) through the cloud's points; RMS of
// the perpendicular residuals.
struct PlaneFit {
    Eigen::Vector3d normal;
    double distance = 0;
    double rms = 0;
    std::size_t points = 0;
};

PlaneFit fit_plane(const fpp::PointCloud& cloud) {
    std::vector<Eigen::Vector3d> pts;
    for (std::size_t i = 0; i < cloud.xyz.pixel_count(); ++i) {
        const float* p = cloud.xyz.data() + 3 * i;
        if (std::isfinite(p[2]))
            pts.emplace_back(double(p[0]), double(p[1]), double(p[2]));
    }
    PlaneFit f;
    f.points = pts.size();
    if (pts.size() < 3)
        return f;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : pts)
        mean += p;
    mean /= double(pts.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : pts)
        cov += (p - mean) * (p - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    f.normal = eig.eigenvectors().col(0);
    if (f.normal.z() < 0)
        f.normal = -f.normal;
    f.distance = f.normal.dot(mean);
    double sum = 0;
    for (const auto& p : pts) {
        const double r = f.normal.dot(p) - f.distance;
        sum += r * r;
    }
    f.rms = std::sqrt(sum / double(pts.size()));
    return f;
}

// --- Geometry alone: true correspondences in, true points out. ---------------

struct TruthScene {
    fpp::sim::Rig rig;
    fpp::Image<float> xyz;
    fpp::Image<float> projector;
};

const TruthScene& composite_truth() {
    static const TruthScene t = [] {
        TruthScene s;
        s.rig = test_rig();
        const fpp::sim::Renderer renderer(s.rig, fpp::sim::named_scene("composite"));
        s.xyz = renderer.truth_xyz();
        s.projector = renderer.truth_projector();
        return s;
    }();
    return t;
}

TEST(SvReconstruct, CameraRaysAreThoseOfTheLensModel) {
    const TruthScene& t = composite_truth();
    const SvReconstructor sv(fpp::calib::calibration_from_rig(t.rig));
    const auto& rays = sv.camera_rays();
    ASSERT_EQ(rays.size(), t.rig.camera_size);
    ASSERT_EQ(rays.channels(), 2);
    // Every pixel of the paper camera is invertible (k3 = 5.08 folds only
    // outside the sensor), and the ray reprojects onto its pixel.
    for (int v = 0; v < rays.height(); v += 7)
        for (int u = 0; u < rays.width(); u += 7) {
            const double xn = double(rays.at(u, v, 0)), yn = double(rays.at(u, v, 1));
            ASSERT_TRUE(std::isfinite(xn) && std::isfinite(yn)) << u << "," << v;
            const fpp::Vec2 px = t.rig.camera.project({xn * 500, yn * 500, 500});
            EXPECT_NEAR(px[0], u, 2e-4);
            EXPECT_NEAR(px[1], v, 2e-4);
        }
}

TEST(SvReconstruct, TrueCorrespondencesGiveTruePointsXY) {
    const TruthScene& t = composite_truth();
    const SvReconstructor sv(fpp::calib::calibration_from_rig(t.rig));
    fpp::PointCloud cloud;
    const SvStats stats =
        sv.reconstruct(from_truth(t.projector), ReconstructAxes::automatic, cloud);
    EXPECT_EQ(stats.axes, ReconstructAxes::xy);
    const ErrorStats e = compare(cloud, t.xyz, t.projector);
    std::printf("geometry only, x+y: %zu points, RMS %.2e mm, max %.2e mm, ray gap RMS %.2e mm\n",
                e.compared, e.rms, e.max, stats.rms_ray_gap_mm);
    // Every pixel the projector lights has a point.
    EXPECT_EQ(stats.points, stats.decoded);
    EXPECT_EQ(stats.rejected, 0u);
    EXPECT_EQ(e.missing, 0u); // every lit pixel
    // float32 inputs (projector coordinates ~1e3 px, eps 6e-5 px) and outputs
    // (500 mm, eps 3e-5 mm) bound what can be reached.
    EXPECT_LT(e.rms, 2e-4);
    EXPECT_LT(e.max, 1e-3);
    EXPECT_LT(stats.max_ray_gap_mm, 1e-3);
    // Intensity and quality come from the decode result.
    for (std::size_t i = 0; i < cloud.xyz.pixel_count(); ++i)
        if (std::isfinite(cloud.xyz.data()[3 * i + 2])) {
            EXPECT_EQ(cloud.quality.data()[i], 100.0f);
            EXPECT_EQ(cloud.intensity.data()[i], 120.0f);
            break;
        }
}

TEST(SvReconstruct, TrueColumnsGiveTruePointsXOnly) {
    const TruthScene& t = composite_truth();
    const SvReconstructor sv(fpp::calib::calibration_from_rig(t.rig));
    fpp::PointCloud cloud;
    const SvStats stats = sv.reconstruct(from_truth(t.projector), ReconstructAxes::x, cloud);
    EXPECT_EQ(stats.axes, ReconstructAxes::x);
    const ErrorStats e = compare(cloud, t.xyz, t.projector);
    std::printf("geometry only, x only (Newton): %zu points, RMS %.2e mm, max %.2e mm, "
                "%.2f steps per point, at most %d\n",
                e.compared, e.rms, e.max, stats.mean_iterations(), stats.max_iterations);
    EXPECT_EQ(stats.points, stats.decoded);
    EXPECT_EQ(stats.not_converged, 0u);
    EXPECT_LT(e.rms, 2e-4);
    EXPECT_LT(e.max, 1e-3);
    // Newton from the distortion-free plane: quadratic convergence.
    EXPECT_LE(stats.max_iterations, 4);
}

TEST(SvReconstruct, PaperPlaneIterationConvergesToTheSamePoints) {
    const TruthScene& t = composite_truth();
    const StereoCalibration calibration = fpp::calib::calibration_from_rig(t.rig);
    SvOptions paper;
    paper.solver = fpp::calib::XOnlySolver::plane_iteration;
    const SvReconstructor newton(calibration);
    const SvReconstructor iterated(calibration, paper);
    const fpp::DecodeResult decoded = from_truth(t.projector);
    fpp::PointCloud a, b;
    const SvStats sa = newton.reconstruct(decoded, ReconstructAxes::x, a);
    const SvStats sb = iterated.reconstruct(decoded, ReconstructAxes::x, b);
    std::printf("paper's plane iteration: %.2f iterations per point, at most %d, %zu not "
                "converged\n",
                sb.mean_iterations(), sb.max_iterations, sb.not_converged);
    EXPECT_EQ(sb.not_converged, 0u);
    EXPECT_EQ(sb.points, sa.points);
    EXPECT_LE(sb.max_iterations, 10); // converges for the paper's projector distortion
    double worst = 0;
    for (std::size_t i = 0; i < a.xyz.pixel_count() * 3; ++i)
        if (std::isfinite(a.xyz.data()[i]))
            worst = std::max(worst, double(std::fabs(a.xyz.data()[i] - b.xyz.data()[i])));
    EXPECT_LT(worst, 1e-4) << "mm";
}

TEST(SvReconstruct, IgnoringProjectorDistortionWouldBeMeasurablyWrong) {
    // The compensation matters at this rig's scale: without it, the same true
    // correspondences land tenths of a millimetre off.
    const TruthScene& t = composite_truth();
    StereoCalibration no_distortion = fpp::calib::calibration_from_rig(t.rig);
    no_distortion.projector.k1 = no_distortion.projector.k2 = no_distortion.projector.k3 = 0;
    no_distortion.projector.p1 = no_distortion.projector.p2 = 0;
    const SvReconstructor sv(no_distortion);
    fpp::PointCloud cloud;
    sv.reconstruct(from_truth(t.projector), ReconstructAxes::x, cloud);
    const ErrorStats e = compare(cloud, t.xyz, t.projector);
    std::printf("x only without projector distortion: RMS %.3f mm, max %.3f mm\n", e.rms, e.max);
    EXPECT_GT(e.max, 0.1);
}

TEST(SvReconstruct, SinglePixelFunctionsMatchTheImageLoop) {
    const TruthScene& t = composite_truth();
    const SvReconstructor sv(fpp::calib::calibration_from_rig(t.rig));
    int checked = 0;
    for (int v = 5; v < t.xyz.height(); v += 37)
        for (int u = 3; u < t.xyz.width(); u += 41) {
            const float px = t.projector.at(u, v, 0), py = t.projector.at(u, v, 1);
            if (!std::isfinite(px) || !std::isfinite(py))
                continue;
            fpp::Vec3 a{}, b{};
            int iterations = -1;
            double gap = -1;
            ASSERT_TRUE(sv.triangulate_x(u, v, double(px), a, &iterations));
            ASSERT_TRUE(sv.triangulate_xy(u, v, double(px), double(py), b, &gap));
            EXPECT_GE(iterations, 1);
            EXPECT_LT(gap, 1e-3);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(a[std::size_t(c)], double(t.xyz.at(u, v, c)), 1e-3);
                EXPECT_NEAR(b[std::size_t(c)], double(t.xyz.at(u, v, c)), 1e-3);
            }
            // The x-only point projects onto the decoded column to the tolerance.
            const fpp::Vec3 in_projector = fpp::mul(t.rig.R, a);
            const fpp::Vec3 p{in_projector[0] + t.rig.t[0], in_projector[1] + t.rig.t[1],
                              in_projector[2] + t.rig.t[2]};
            EXPECT_NEAR(t.rig.projector.project(p)[0], double(px), 1e-5);
            ++checked;
        }
    EXPECT_GT(checked, 20);
}

TEST(SvReconstruct, RejectsColumnsOutsideTheProjectorAndInconsistentRays) {
    const TruthScene& t = composite_truth();
    const StereoCalibration calibration = fpp::calib::calibration_from_rig(t.rig);
    const int u = 200, v = 150;
    const float px = t.projector.at(u, v, 0), py = t.projector.at(u, v, 1);
    ASSERT_TRUE(std::isfinite(px));
    fpp::Vec3 p{};
    const SvReconstructor sv(calibration);
    EXPECT_FALSE(sv.triangulate_x(u, v, -5.0, p));   // left of the projector image
    EXPECT_FALSE(sv.triangulate_x(u, v, 1290.0, p)); // right of it (1280 wide)
    // A row 3 px off: the rays miss each other by about a millimetre.
    double gap = 0;
    ASSERT_TRUE(sv.triangulate_xy(u, v, double(px), double(py) + 3, p, &gap));
    EXPECT_GT(gap, 0.3);
    SvOptions strict;
    strict.max_ray_gap_mm = 0.1;
    const SvReconstructor strict_sv(calibration, strict);
    EXPECT_FALSE(strict_sv.triangulate_xy(u, v, double(px), double(py) + 3, p, &gap));
    EXPECT_TRUE(strict_sv.triangulate_xy(u, v, double(px), double(py), p, &gap));
}

TEST(SvReconstruct, ResultsDoNotDependOnThreadsOrReuse) {
    const TruthScene& t = composite_truth();
    const StereoCalibration calibration = fpp::calib::calibration_from_rig(t.rig);
    SvOptions one;
    one.threads = 1;
    SvOptions two;
    two.threads = 2;
    const SvReconstructor a(calibration, one);
    const SvReconstructor b(calibration, two);
    const fpp::DecodeResult decoded = from_truth(t.projector);
    fpp::DecodeResult other = decoded; // a second "scan": shifted columns
    for (std::size_t i = 0; i < other.proj_x.pixel_count(); ++i)
        other.proj_x.data()[i] += 1.0f;

    fpp::PointCloud ca, cb, reused;
    a.reconstruct(decoded, ReconstructAxes::x, ca);
    b.reconstruct(decoded, ReconstructAxes::x, cb);
    b.reconstruct(other, ReconstructAxes::xy, reused); // leaves state in `reused`
    b.reconstruct(decoded, ReconstructAxes::x, reused);
    const std::size_t bytes = ca.xyz.pixel_count() * 3 * sizeof(float);
    EXPECT_EQ(std::memcmp(ca.xyz.data(), cb.xyz.data(), bytes), 0);
    // NaN bit patterns compare equal too: one canonical NaN everywhere.
    EXPECT_EQ(std::memcmp(cb.xyz.data(), reused.xyz.data(), bytes), 0);
    EXPECT_EQ(std::memcmp(cb.quality.data(), reused.quality.data(),
                          cb.quality.pixel_count() * sizeof(float)),
              0);
}

TEST(SvReconstruct, MisuseIsRejected) {
    const TruthScene& t = composite_truth();
    StereoCalibration calibration = fpp::calib::calibration_from_rig(t.rig);
    const SvReconstructor sv(calibration);
    fpp::DecodeResult decoded = from_truth(t.projector);
    fpp::PointCloud cloud;
    fpp::DecodeResult x_only = decoded;
    x_only.proj_y = {};
    EXPECT_THROW(sv.reconstruct(x_only, ReconstructAxes::xy, cloud), std::invalid_argument);
    EXPECT_EQ(fpp::calib::resolve_axes(x_only, ReconstructAxes::automatic), ReconstructAxes::x);
    fpp::DecodeResult y_only = decoded;
    y_only.proj_x = {};
    EXPECT_THROW(sv.reconstruct(y_only, ReconstructAxes::automatic, cloud), std::invalid_argument);
    fpp::DecodeResult wrong_size;
    wrong_size.proj_x = fpp::Image<float>(10, 10, 1);
    EXPECT_THROW(sv.reconstruct(wrong_size, ReconstructAxes::x, cloud), std::invalid_argument);
    calibration.projector_size = {0, 0};
    EXPECT_THROW(SvReconstructor{calibration}, std::invalid_argument);
    EXPECT_EQ(fpp::calib::parse_axes("xy"), ReconstructAxes::xy);
    EXPECT_THROW(fpp::calib::parse_axes("z"), std::invalid_argument);
}

// --- The whole chain: frames rendered, decoded, reconstructed. ---------------

struct ChainResult {
    ErrorStats xy, x;
    SvStats xy_stats, x_stats;
    PlaneFit plane_xy, plane_x;
};

ChainResult run_chain(const fpp::sim::Rig& rig, const char* scene, bool smooth_only) {
    const fpp::sim::Renderer renderer(rig, fpp::sim::named_scene(scene));
    const fpp::sim::SimulatedCapture sim =
        fpp::sim::simulate(renderer, fpp::standard_sequence("gray-xy", rig.projector_size), 7);
    fpp::CaptureSet capture;
    capture.manifest = sim.manifest;
    capture.frames = sim.frames;
    const fpp::DecodeResult decoded = fpp::decode(capture);
    const SvReconstructor sv(fpp::calib::calibration_from_rig(rig.without_effects()));
    ChainResult r;
    fpp::PointCloud cxy, cx;
    r.xy_stats = sv.reconstruct(decoded, ReconstructAxes::xy, cxy);
    r.x_stats = sv.reconstruct(decoded, ReconstructAxes::x, cx);
    const std::vector<bool> smooth = smooth_pixels(sim.truth_xyz);
    r.xy = compare(cxy, sim.truth_xyz, sim.truth_projector, smooth_only ? &smooth : nullptr);
    r.x = compare(cx, sim.truth_xyz, sim.truth_projector, smooth_only ? &smooth : nullptr);
    r.plane_xy = fit_plane(cxy);
    r.plane_x = fit_plane(cx);
    std::printf("%s%s: x+y RMS %.4f mm (z %.4f), max %.4f mm over %zu points, %zu missing; "
                "x only RMS %.4f mm (z %.4f), max %.4f mm over %zu points, %zu missing, %.2f "
                "steps/point; coverage of lit pixels %.4f (x+y), %.4f (x)\n",
                scene, smooth_only ? " (continuous surface)" : "", r.xy.rms, r.xy.rms_z, r.xy.max,
                r.xy.compared, r.xy.missing, r.x.rms, r.x.rms_z, r.x.max, r.x.compared, r.x.missing,
                r.x_stats.mean_iterations(), r.xy.coverage(), r.x.coverage());
    return r;
}

TEST(SvReconstructSimulated, PlaneAtMidVolumeNoiseFree) {
    const ChainResult r = run_chain(test_rig(), "plane", false);
    std::printf("plane fit: x+y RMS %.4f mm at %.4f mm, x only RMS %.4f mm at %.4f mm\n",
                r.plane_xy.rms, r.plane_xy.distance, r.plane_x.rms, r.plane_x.distance);
    EXPECT_LT(r.xy.rms, 0.01);
    EXPECT_LT(r.x.rms, 0.01);
    EXPECT_LT(r.xy.max, 0.05);
    EXPECT_LT(r.x.max, 0.05);
    // The plane (z = 480 mm, facing the camera) comes back flat and in place.
    EXPECT_LT(r.plane_xy.rms, 0.01);
    EXPECT_LT(r.plane_x.rms, 0.01);
    EXPECT_GT(r.plane_xy.normal.z(), 1 - 1e-6);
    EXPECT_NEAR(r.plane_xy.distance, 480.0, 0.005);
    EXPECT_NEAR(r.plane_x.distance, 480.0, 0.005);
    EXPECT_EQ(r.x_stats.not_converged, 0u);
    EXPECT_GT(r.xy.coverage(), 0.999);
    EXPECT_GT(r.x.coverage(), 0.999);
}

TEST(SvReconstructSimulated, CompositeSceneNoiseFree) {
    const ChainResult r = run_chain(test_rig(), "composite", true);
    EXPECT_LT(r.xy.rms, 0.01);
    EXPECT_LT(r.x.rms, 0.01);
    EXPECT_EQ(r.x_stats.not_converged, 0u);
    EXPECT_GT(r.xy.coverage(), 0.99);
    EXPECT_GT(r.x.coverage(), 0.99);
}

TEST(SvReconstructSimulated, PlaneWithOneDnReadNoise) {
    fpp::sim::Rig rig = test_rig();
    rig.sensor.read_noise_dn = 1.0;
    const ChainResult r = run_chain(rig, "plane", false);
    std::printf("plane fit with 1 DN read noise: x+y RMS %.4f mm, x only RMS %.4f mm\n",
                r.plane_xy.rms, r.plane_x.rms);
    // Phase noise ~ sqrt(2/8) * 1 DN / B (B ~ 100 DN) ~ 0.005 rad ~ 0.015 px
    // at period 20, about 0.01 mm in depth at 480 mm.
    EXPECT_LT(r.xy.rms, 0.03);
    EXPECT_LT(r.x.rms, 0.03);
    EXPECT_LT(r.plane_xy.rms, 0.03);
    EXPECT_NEAR(r.plane_xy.distance, 480.0, 0.01);
}

// The names --axes takes, one per value, each read back; an unknown one is
// refused naming them all.
TEST(SvReconstruct, AxesNamesReadBack) {
    using fpp::calib::parse_axes, fpp::calib::to_string;
    EXPECT_STREQ(to_string(ReconstructAxes::automatic), "auto");
    EXPECT_STREQ(to_string(ReconstructAxes::x), "x");
    EXPECT_STREQ(to_string(ReconstructAxes::xy), "xy");
    for (const char* name : {"auto", "x", "xy"})
        EXPECT_STREQ(to_string(parse_axes(name)), name);
    try {
        parse_axes("yx");
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "unknown axes 'yx' (auto, x, xy)");
    }
}

} // namespace
