// Projector coordinates of checkerboard corners: the three methods against
// the simulator's ground truth, and exactness on synthetic maps.
//
// Measured (paper rig with effects: gamma 2.2, defocus, shot and 1 DN read
// noise; full 1600 x 1200 camera; gray-xy; 11 x 8 board of 15 mm; RMS over
// the corners of 15 session poses, projector px, against truth_proj at the
// detected camera corner):
//   poly (default) 0.0023, homography 0.0036, bilinear 0.057.
// Camera binned 2x (800 x 600): poly 0.0043, homography 0.0046, bilinear 0.062.
// The test below uses 3 of the full-size poses.

#include "fpp/calib/corner_projector.hpp"
#include "fpp/calib/corners.hpp"
#include "fpp/decoder.hpp"
#include "fpp/sequences.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/session.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iostream>

namespace {

using namespace fpp;
using calib::CornerMethod;

TEST(ProjectorCorners, DefaultIsTheMostAccurateMethodOnSimulatedTruth) {
    EXPECT_EQ(calib::ProjectorCornerOptions{}.method, CornerMethod::poly);
    const sim::Rig rig = sim::load_rig(sim::effects_rig_path());
    ASSERT_EQ(rig.sensor.read_noise_dn, 1.0);
    sim::SessionOptions options;
    options.poses = 15;
    const std::vector<sim::Pose> poses = sim::session_poses(rig, options);
    const Sequence sequence = standard_sequence("gray-xy", rig.projector_size);
    std::array<double, 3> sum{};
    int count = 0;
    for (int p : {0, 6, 11}) {
        const sim::SimulatedCapture sim = sim::simulate(
            rig, sim::checkerboard_scene(poses[static_cast<std::size_t>(p)], options.board),
            sequence, 100 + static_cast<std::uint64_t>(p));
        CaptureSet capture;
        capture.manifest = sim.manifest;
        capture.frames = sim.frames;
        const DecodeResult decoded = decode(capture);
        const auto corners =
            calib::find_checkerboard(calib::corner_textures(capture, decoded), 11, 8);
        ASSERT_TRUE(corners.found) << corners.failure;
        for (int m = 0; m < 3; ++m) {
            calib::ProjectorCornerOptions o;
            o.method = static_cast<CornerMethod>(m);
            const auto pc = calib::projector_corners(decoded, corners.points, 11, 8,
                                                     corners.origin_square_black, o);
            ASSERT_EQ(pc.failed, 0) << calib::to_string(o.method);
            for (std::size_t k = 0; k < pc.points.size(); ++k) {
                const Vec2& c = corners.points[k];
                const double tx = calib::sample_bilinear(sim.truth_projector, c[0], c[1], 0);
                const double ty = calib::sample_bilinear(sim.truth_projector, c[0], c[1], 1);
                ASSERT_TRUE(std::isfinite(tx) && std::isfinite(ty));
                sum[static_cast<std::size_t>(m)] +=
                    std::pow(pc.points[k][0] - tx, 2) + std::pow(pc.points[k][1] - ty, 2);
                if (m == 0)
                    ++count;
            }
        }
    }
    const double poly = std::sqrt(sum[0] / count), bilinear = std::sqrt(sum[1] / count),
                 homography = std::sqrt(sum[2] / count);
    std::cout << "projector corner RMS error vs truth (projector px): poly " << poly
              << ", homography " << homography << ", bilinear " << bilinear << "\n";
    EXPECT_LT(poly, homography);
    EXPECT_LT(homography, bilinear);
    EXPECT_LT(poly, 0.004);
    EXPECT_LT(homography, 0.006);
    EXPECT_GT(bilinear, 0.03); // the black squares' noise and the edge bias
}

// A synthetic decode: camera 240 x 200, a 6 x 5 grid of corners every 32 px
// (origin square black), projector maps given as functions of the pixel.
template <class MapX, class MapY> DecodeResult synthetic_decode(MapX fx, MapY fy) {
    DecodeResult d;
    d.camera = {240, 200};
    d.proj_x = Image<float>(d.camera);
    d.proj_y = Image<float>(d.camera);
    d.mask = Image<std::uint8_t>(d.camera, 1, kDecodeValid);
    for (int y = 0; y < d.camera.height; ++y)
        for (int x = 0; x < d.camera.width; ++x) {
            d.proj_x.at(x, y) = static_cast<float>(fx(x, y));
            d.proj_y.at(x, y) = static_cast<float>(fy(x, y));
        }
    return d;
}

std::vector<Vec2> grid_corners() {
    std::vector<Vec2> c;
    for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 6; ++i)
            c.push_back({40.3 + 32 * i, 36.7 + 32 * j});
    return c;
}

TEST(ProjectorCorners, PolynomialAndHomographyAreExactOnTheirOwnMaps) {
    const std::vector<Vec2> corners = grid_corners();
    // Cubic map: the 5th-order fit reproduces it (float storage: ~1e-4 px).
    auto cx = [](double x, double y) {
        return 100 + 1.3 * x + 0.2 * y + 4e-4 * x * y - 2e-6 * x * x * x;
    };
    auto cy = [](double x, double y) {
        return 50 - 0.1 * x + 1.1 * y + 3e-4 * y * y + 1e-6 * x * y * y;
    };
    const DecodeResult cubic = synthetic_decode(cx, cy);
    const auto poly = calib::projector_corners(cubic, corners, 6, 5, true);
    ASSERT_EQ(poly.failed, 0);
    for (std::size_t k = 0; k < corners.size(); ++k) {
        EXPECT_NEAR(poly.points[k][0], cx(corners[k][0], corners[k][1]), 2e-4);
        EXPECT_NEAR(poly.points[k][1], cy(corners[k][0], corners[k][1]), 2e-4);
    }
    // Projective map: the local homography reproduces it.
    auto hw = [](double x, double y) { return 1 + 2e-4 * x - 1e-4 * y; };
    auto hx = [&](double x, double y) { return (300 + 1.5 * x + 0.1 * y) / hw(x, y); };
    auto hy = [&](double x, double y) { return (20 + 0.05 * x + 1.4 * y) / hw(x, y); };
    calib::ProjectorCornerOptions o;
    o.method = CornerMethod::homography;
    const auto homography =
        calib::projector_corners(synthetic_decode(hx, hy), corners, 6, 5, true, o);
    ASSERT_EQ(homography.failed, 0);
    for (std::size_t k = 0; k < corners.size(); ++k) {
        EXPECT_NEAR(homography.points[k][0], hx(corners[k][0], corners[k][1]), 2e-4);
        EXPECT_NEAR(homography.points[k][1], hy(corners[k][0], corners[k][1]), 2e-4);
    }
    // Bilinear sampling is exact on an affine map.
    o.method = CornerMethod::bilinear;
    auto ax = [](double x, double y) { return 3 + 1.25 * x - 0.5 * y; };
    auto ay = [](double x, double y) { return 7 + 0.25 * x + 0.75 * y; };
    const auto bilinear =
        calib::projector_corners(synthetic_decode(ax, ay), corners, 6, 5, true, o);
    for (std::size_t k = 0; k < corners.size(); ++k) {
        EXPECT_NEAR(bilinear.points[k][0], ax(corners[k][0], corners[k][1]), 1e-4);
        EXPECT_NEAR(bilinear.points[k][1], ay(corners[k][0], corners[k][1]), 1e-4);
    }
}

// Pixels decoded to the wrong fringe (a whole period off) inside the white
// squares must not pull the fit.
TEST(ProjectorCorners, WrongFringePixelsAreRejected) {
    const std::vector<Vec2> corners = grid_corners();
    auto fx = [](double x, double y) { return 10 + 1.2 * x + 0.3 * y; };
    auto fy = [](double x, double y) { return 5 + 0.2 * x + 1.1 * y; };
    DecodeResult d = synthetic_decode(fx, fy);
    for (int y = 0; y < d.camera.height; y += 7)
        for (int x = 0; x < d.camera.width; x += 11)
            d.proj_x.at(x, y) += 20.0f;
    for (CornerMethod m : {CornerMethod::poly, CornerMethod::homography}) {
        calib::ProjectorCornerOptions o;
        o.method = m;
        const auto r = calib::projector_corners(d, corners, 6, 5, true, o);
        ASSERT_EQ(r.failed, 0);
        for (std::size_t k = 0; k < corners.size(); ++k)
            EXPECT_NEAR(r.points[k][0], fx(corners[k][0], corners[k][1]), 1e-3)
                << calib::to_string(m) << " corner " << k;
    }
}

TEST(ProjectorCorners, CornersWithoutDecodedPixelsFailAndAreCounted) {
    const std::vector<Vec2> corners = grid_corners();
    DecodeResult d =
        synthetic_decode([](double x, double) { return x; }, [](double, double y) { return y; });
    // Nothing decoded on the left third of the image.
    for (int y = 0; y < d.camera.height; ++y)
        for (int x = 0; x < 80; ++x) {
            d.mask.at(x, y) = kDecodeLowModulation;
            d.proj_x.at(x, y) = d.proj_y.at(x, y) = std::numeric_limits<float>::quiet_NaN();
        }
    for (CornerMethod m : {CornerMethod::poly, CornerMethod::bilinear, CornerMethod::homography}) {
        calib::ProjectorCornerOptions o;
        o.method = m;
        const auto r = calib::projector_corners(d, corners, 6, 5, true, o);
        int failed = 0;
        for (std::size_t k = 0; k < corners.size(); ++k) {
            if (corners[k][0] < 60) {
                EXPECT_FALSE(r.valid[k]) << calib::to_string(m) << " corner " << k;
                EXPECT_TRUE(std::isnan(r.points[k][0]));
            }
            if (corners[k][0] > 150) {
                EXPECT_TRUE(r.valid[k]) << calib::to_string(m) << " corner " << k;
            }
            failed += r.valid[k] ? 0 : 1;
        }
        EXPECT_EQ(failed, r.failed);
        EXPECT_GE(r.failed, 5);
    }
}

TEST(ProjectorCorners, NeedsBothAxesAndNamesMethods) {
    DecodeResult d =
        synthetic_decode([](double x, double) { return x; }, [](double, double y) { return y; });
    d.proj_y = Image<float>();
    EXPECT_THROW(calib::projector_corners(d, grid_corners(), 6, 5, true), std::invalid_argument);
    EXPECT_EQ(calib::corner_method_from_string("homography"), CornerMethod::homography);
    EXPECT_THROW(calib::corner_method_from_string("cubic"), std::invalid_argument);
}

} // namespace
