// Simulated acceptance of the stereo calibration (the default procedure:
// the camera first from its corners, then the projector with the boards
// held, correction grids): the paper rig with its effects on (unmodelled
// projector distortion k4 + thin prism, gamma 2.2, defocus, shot noise and 1
// DN read noise), a session of 30 checkerboard poses spread through the
// volume, 8-step phase with Gray code in x and y (gray-xy).
//
// Checked against ground truth:
//   - camera and projector reprojection RMS <= 0.1 px;
//   - the recovered models (lens and correction grid) reproduce the true
//     projections of a grid of points spanning the volume (400-560 mm, whole
//     camera field) within 0.1 px RMS, camera and projector;
//   - SV reconstruction (x only) of a flat board in the middle of the volume
//     within 0.05 mm RMS of the TRUE plane, its mean (bias) within 0.03 mm
//     (0.015 mm at full size);
//   - every pose's corner 0 is the board's own corner (0, 0).
//
// Measured (Release, this machine; the test prints its figures):
//                          camera binned 2x (800 x 600)   full size (1600 x 1200)
//   reprojection RMS       camera 0.0056, projector 0.0083   0.0039, 0.0033 px
//   models vs truth        camera 0.033 (max 0.085),         0.050 (max 0.072),
//                          projector 0.049 (max 0.082) px    0.026 (max 0.036) px
//   skew                   camera 0.426 (true 0.42),         0.843 (true 0.84),
//                          projector 0.828 (true 0.83)       0.825 (true 0.83)
//   plane vs true plane    0.034 mm RMS, mean 0.019          0.031 mm RMS, mean 0.011
//   session, calibration   ~10 s, ~13 s                      ~31 s, ~37 s
// The plane's RMS is mostly the scan's own noise (0.028 mm with the rig's
// exact model); its mean is the camera's: the camera alone places the
// boards, and its focal length from 30 poses' corners is good to about
// 2.5e-5 (binned) and 1e-5 (full size) of itself, which is 0.012 and 0.005 mm
// of depth at 480 mm.
//
// The rig's unmodelled projector distortion (0.3 to 0.5 px at the projector's
// top corners; 0.07 px RMS, 0.3 px max over the part of the projector image
// the camera sees) stays on: reconstructed with the rig's own 5-coefficient
// model it leaves 0.050 mm RMS on the plane (0.0055 mm with every effect
// off); the projector's correction grid takes it up.
//
// The full-size run takes minutes under the sanitizers; it runs in optimised
// builds without them only (the binned run covers the same code).

#include "test_support.hpp"

#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/stereo_session.hpp"
#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/decoder.hpp"
#include "fpp/sequences.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"
#include "fpp/simulator/session.hpp"

#include <gtest/gtest.h>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>

namespace fpp::test {
namespace {

struct ProjectionCheck {
    double camera_rms = 0, camera_max = 0;       // px
    double projector_rms = 0, projector_max = 0; // px
    int camera_points = 0, projector_points = 0;
};

inline ProjectionCheck check_intrinsics(const sim::Rig& rig, const calib::StereoCalibration& c) {
    ProjectionCheck out;
    double sc = 0, sp = 0;
    const int nx = 17, ny = 13;
    for (double z = 400; z <= 560.5; z += 40)
        for (int iy = 0; iy < ny; ++iy)
            for (int ix = 0; ix < nx; ++ix) {
                const Vec2 pixel{ix * (rig.camera_size.width - 1.0) / (nx - 1),
                                 iy * (rig.camera_size.height - 1.0) / (ny - 1)};
                Vec2 n{};
                if (!rig.camera.pixel_to_normalised(pixel, n))
                    continue;
                const Vec3 X{n[0] * z, n[1] * z, z};
                const Vec2 cam = c.camera_pixel(X);
                const double ec = std::hypot(cam[0] - pixel[0], cam[1] - pixel[1]);
                sc += ec * ec;
                out.camera_max = std::max(out.camera_max, ec);
                ++out.camera_points;
                const Vec3 xt = mul(rig.R, X);
                const Vec2 pt =
                    rig.projector.project({xt[0] + rig.t[0], xt[1] + rig.t[1], xt[2] + rig.t[2]});
                if (!(pt[0] >= 0 && pt[1] >= 0 && pt[0] <= rig.projector_size.width - 1 &&
                      pt[1] <= rig.projector_size.height - 1))
                    continue;
                const Vec2 pe = c.projector_pixel(X);
                const double ep = std::hypot(pe[0] - pt[0], pe[1] - pt[1]);
                sp += ep * ep;
                out.projector_max = std::max(out.projector_max, ep);
                ++out.projector_points;
            }
    out.camera_rms = std::sqrt(sc / std::max(1, out.camera_points));
    out.projector_rms = std::sqrt(sp / std::max(1, out.projector_points));
    return out;
}

struct PlaneCheck {
    double rms_mm = 0;       // distance to the true plane
    double mean_mm = 0;      // signed (bias along the normal)
    double max_mm = 0;       // largest |distance| (after dropping nothing)
    double truth_rms_mm = 0; // 3D distance to truth_xyz at the same pixel
    std::size_t points = 0;
};

// The test plane: centre 480 mm, tilted 8 deg about x and -12 deg about y,
// large enough to fill the camera field.
inline sim::Pose test_plane_pose() {
    return sim::Pose::from_euler_deg({0, 0, 480}, 8, -12, 0);
}

inline PlaneCheck check_plane(const sim::Rig& rig, const calib::StereoCalibration& c,
                              std::uint64_t seed = 77) {
    const sim::Pose pose = test_plane_pose();
    sim::Scene scene;
    scene.add(std::make_unique<sim::Plane>(pose, 600, 500, 0.85));
    const sim::SimulatedCapture sim =
        sim::simulate(rig, scene, standard_sequence("gray-x", rig.projector_size), seed);
    CaptureSet capture;
    capture.manifest = sim.manifest;
    capture.frames = sim.frames;
    const DecodeResult decoded = decode(capture);
    const calib::SvReconstructor sv(c);
    PointCloud cloud;
    sv.reconstruct(decoded, calib::ReconstructAxes::x, cloud);
    const Vec3 normal{pose.R[2], pose.R[5], pose.R[8]};
    PlaneCheck out;
    double s = 0, m = 0, st = 0;
    const std::size_t n = cloud.xyz.pixel_count();
    for (std::size_t i = 0; i < n; ++i) {
        const float* pf = cloud.xyz.data() + 3 * i;
        if (!std::isfinite(pf[0]) || !std::isfinite(pf[1]) || !std::isfinite(pf[2]))
            continue;
        const Vec3 p{static_cast<double>(pf[0]), static_cast<double>(pf[1]),
                     static_cast<double>(pf[2])};
        const double d = normal[0] * (p[0] - pose.centre[0]) + normal[1] * (p[1] - pose.centre[1]) +
                         normal[2] * (p[2] - pose.centre[2]);
        s += d * d;
        m += d;
        out.max_mm = std::max(out.max_mm, std::fabs(d));
        const float* t = sim.truth_xyz.data() + 3 * i;
        if (std::isfinite(t[0]))
            st += std::pow(p[0] - static_cast<double>(t[0]), 2) +
                  std::pow(p[1] - static_cast<double>(t[1]), 2) +
                  std::pow(p[2] - static_cast<double>(t[2]), 2);
        ++out.points;
    }
    if (out.points) {
        const double count = static_cast<double>(out.points);
        out.rms_mm = std::sqrt(s / count);
        out.mean_mm = m / count;
        out.truth_rms_mm = std::sqrt(st / count);
    }
    return out;
}

// The rig's own geometry as a calibration (the calibrated part of its lens
// models only): the floor a perfect 5-coefficient calibration reaches.
inline calib::StereoCalibration rig_five_coefficient_model(const sim::Rig& rig) {
    calib::StereoCalibration c;
    c.camera_size = rig.camera_size;
    c.projector_size = rig.projector_size;
    c.camera = rig.camera;
    c.projector = rig.projector;
    c.camera.drop_unmodelled_terms();
    c.projector.drop_unmodelled_terms();
    c.R = rig.R;
    c.T = rig.t;
    return c;
}

struct Acceptance {
    calib::SessionResult result;
    ProjectionCheck intrinsics;
    PlaneCheck plane;
    PlaneCheck plane_rig_model;           // reconstructed with the rig's own 5-coefficient model
    ProjectionCheck intrinsics_rig_model; // the rig's own 5-coefficient model: the floor
    double origin_max_px = 0; // corner 0 against the board's corner (0, 0), over the poses
    double seconds_session = 0, seconds_calibration = 0;
};

Acceptance run_acceptance(int binning) {
    Acceptance a;
    sim::Rig rig = sim::load_rig(sim::effects_rig_path());
    EXPECT_EQ(rig.sensor.read_noise_dn, 1.0);
    EXPECT_NE(rig.projector.k4, 0.0); // the unmodelled distortion stays on
    EXPECT_NE(rig.projector.s1, 0.0);
    if (binning > 1)
        rig = rig.binned_camera(binning);
    TempDir dir;
    sim::SessionOptions options;
    options.poses = 30;
    auto t0 = std::chrono::steady_clock::now();
    sim::write_session(dir / "session", rig, standard_sequence("gray-xy", rig.projector_size),
                       options);
    a.seconds_session =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    t0 = std::chrono::steady_clock::now();
    calib::StereoSessionOptions so;
    a.result = calib::calibrate_session(dir / "session", so);
    a.seconds_calibration =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const calib::StereoCalibration& c = a.result.stereo.calibration;
    a.intrinsics = check_intrinsics(rig, c);
    a.plane = check_plane(rig, c);
    a.plane_rig_model = check_plane(rig, rig_five_coefficient_model(rig));
    a.intrinsics_rig_model = check_intrinsics(rig, rig_five_coefficient_model(rig));
    // Corner 0 of every pose against the true corner (0, 0) (metadata pose).
    for (const calib::SessionPose& p : a.result.poses) {
        const YAML::Node meta = YAML::Load(read_manifest(p.folder / "capture.yaml").metadata_yaml);
        sim::Pose pose;
        for (std::size_t k = 0; k < 3; ++k)
            pose.centre[k] = meta["board_pose"]["centre_mm"][k].as<double>();
        for (std::size_t k = 0; k < 9; ++k)
            pose.R[k] = meta["board_pose"]["rotation"][k].as<double>();
        const Vec2 truth =
            rig.camera.project(sim::Checkerboard(pose, options.board).inner_corners()[0]);
        a.origin_max_px = std::max(a.origin_max_px, std::hypot(truth[0] - p.corners.points[0][0],
                                                               truth[1] - p.corners.points[0][1]));
    }
    const LensModel& sigma = a.result.stereo.camera_sigma;
    std::cout << "camera " << rig.camera_size.width << " x " << rig.camera_size.height
              << ": session " << a.seconds_session << " s, calibration " << a.seconds_calibration
              << " s\n"
              << "reprojection RMS: camera " << c.camera_rms << " px, projector " << c.projector_rms
              << " px\n"
              << "intrinsics vs truth over the volume: camera " << a.intrinsics.camera_rms
              << " px RMS (max " << a.intrinsics.camera_max << "), projector "
              << a.intrinsics.projector_rms << " px RMS (max " << a.intrinsics.projector_max << ", "
              << a.intrinsics.projector_points << " points); the rig's own 5-coefficient "
              << "model: camera " << a.intrinsics_rig_model.camera_rms << " (max "
              << a.intrinsics_rig_model.camera_max << "), projector "
              << a.intrinsics_rig_model.projector_rms << " (max "
              << a.intrinsics_rig_model.projector_max << ")\n"
              << "plane vs true plane: " << a.plane.rms_mm << " mm RMS (mean " << a.plane.mean_mm
              << ", " << a.plane.points << " points); with the rig's own 5-coefficient model "
              << a.plane_rig_model.rms_mm << " mm\n"
              << "camera - truth: principal point " << c.camera.cu - rig.camera.cu << ", "
              << c.camera.cv - rig.camera.cv << " px (sigma " << sigma.cu << ", " << sigma.cv
              << "), focal " << c.camera.fu - rig.camera.fu << ", " << c.camera.fv - rig.camera.fv
              << " px (sigma " << sigma.fu << ", " << sigma.fv << ")\n"
              << "skew: camera " << c.camera.skew << " (true " << rig.camera.skew << "), projector "
              << c.projector.skew << " (true " << rig.projector.skew << ")\n";
    return a;
}

void expect_acceptance(const Acceptance& a, const sim::Rig& rig) {
    const calib::StereoCalibration& c = a.result.stereo.calibration;
    ASSERT_EQ(a.result.poses.size(), 30u);
    EXPECT_EQ(a.result.calibrated.size(), 30u);
    for (const calib::SessionPose& p : a.result.poses)
        EXPECT_TRUE(p.usable) << p.name << ": " << p.skip_reason;
    EXPECT_LE(c.camera_rms, 0.1);
    EXPECT_LE(c.projector_rms, 0.1);
    // The camera against the truth: focal lengths and principal point within
    // three of their own reported sigmas (at 800 x 600 about 0.035 and
    // 0.11 px), and over the volume no farther off than the principal
    // point's three-sigma circle. The over-volume error is mostly the
    // principal point's (measured 0.08 px at 800 x 600, under one sigma): a
    // fixed 0.1 px bound would sit inside the calibration's own noise.
    const LensModel& sigma = a.result.stereo.camera_sigma;
    EXPECT_LE(std::fabs(c.camera.fu - rig.camera.fu), 3 * sigma.fu);
    EXPECT_LE(std::fabs(c.camera.fv - rig.camera.fv), 3 * sigma.fv);
    EXPECT_LE(std::fabs(c.camera.cu - rig.camera.cu), 3 * sigma.cu);
    EXPECT_LE(std::fabs(c.camera.cv - rig.camera.cv), 3 * sigma.cv);
    EXPECT_LE(a.intrinsics.camera_max, 3 * std::hypot(sigma.cu, sigma.cv));
    // The projector: within 0.05 px of the rig's own 5-coefficient model,
    // whose unmodelled k4 and prism terms leave 0.072 px RMS.
    EXPECT_LE(a.intrinsics.projector_rms, a.intrinsics_rig_model.projector_rms + 0.05);
    EXPECT_GT(a.intrinsics.projector_points, 500);
    EXPECT_LE(a.plane.rms_mm, 0.05);
    EXPECT_LE(std::fabs(a.plane.mean_mm), rig.camera_size.width >= 1600 ? 0.015 : 0.03);
    EXPECT_GT(a.plane.points, rig.camera_size.area() / 2);
    EXPECT_LT(a.origin_max_px, 0.05);
    EXPECT_NEAR(c.camera.skew, rig.camera.skew, 0.1);
    EXPECT_NEAR(c.projector.skew, rig.projector.skew, 0.2);
    // The unmodelled projector distortion leaves a measurable SV error with
    // the rig's own 5-coefficient model (what the hybrid model corrects).
    EXPECT_GT(a.plane_rig_model.rms_mm, 0.03);
}

TEST(StereoSimAcceptance, CameraBinned2x) {
    const Acceptance a = run_acceptance(2);
    expect_acceptance(a, sim::load_rig(sim::effects_rig_path()).binned_camera(2));
}

TEST(StereoSimAcceptance, FullSize) {
#if defined(__SANITIZE_ADDRESS__) || !defined(NDEBUG)
    GTEST_SKIP() << "full-size acceptance runs in optimised builds without sanitizers only "
                    "(CameraBinned2x covers the same code)";
#else
    const Acceptance a = run_acceptance(1);
    const sim::Rig rig = sim::load_rig(sim::effects_rig_path());
    expect_acceptance(a, rig);
    // At full size the projector's model holds everywhere in the volume.
    EXPECT_LE(a.intrinsics.projector_max, 0.1);
#endif
}

} // namespace
} // namespace fpp::test
