// The turn between a calibrated and a true camera frame, from the rays alone.

#include "fpp/calib/frame_turn.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace {

using fpp::LensModel;
using fpp::Vec3;
using fpp::calib::camera_frame_turn;
using fpp::calib::FrameTurn;
using fpp::calib::StereoCalibration;

// A 1600 x 1200 pinhole camera (f = 2700 px, centre 799.5, 599.5).
StereoCalibration pinhole_calibration() {
    StereoCalibration c;
    c.camera_size = {1600, 1200};
    c.projector_size = {1280, 800};
    c.camera.fu = c.camera.fv = 2700;
    c.camera.cu = 799.5;
    c.camera.cv = 599.5;
    return c;
}

TEST(FrameTurn, TheSameCameraIsNotTurned) {
    StereoCalibration c = pinhole_calibration();
    LensModel distorted = c.camera;
    distorted.k1 = -0.12;
    distorted.k2 = 0.3;
    StereoCalibration d = pinhole_calibration();
    d.camera = distorted;
    for (const StereoCalibration* cal : {&c, &d}) {
        const FrameTurn turn = camera_frame_turn(*cal, cal->camera);
        EXPECT_LT(turn.angle_rad, 1e-9);
        EXPECT_LT(turn.ray_rms_rad, 1e-9);
        EXPECT_EQ(turn.rays, 200 * 150); // every 8th pixel of 1600 x 1200
    }
}

// A principal point 27 px to the right in the truth: every true ray is the
// calibrated one moved by 27 / f to the left, nearly a turn about y by that
// angle (a turn also bends the image by f w x^2, which a shift does not).
TEST(FrameTurn, APrincipalPointShiftReadsAsATurnAboutTheOtherAxis) {
    const StereoCalibration c = pinhole_calibration();
    LensModel truth = c.camera;
    truth.cu += 27;
    const FrameTurn turn = camera_frame_turn(c, truth);
    const double expected = 27.0 / 2700.0;
    EXPECT_NEAR(turn.angle_rad, expected, 0.03 * expected);
    // X_true = Q X_cal: the optical axis goes to -x (towards the truth's
    // principal point's side of the image, seen from the camera).
    EXPECT_NEAR(turn.Q[2], -std::sin(turn.angle_rad), 1e-4 * turn.angle_rad);
    EXPECT_NEAR(turn.Q[5], 0, 1e-4 * turn.angle_rad);
    // What is left is the bend (up to f w x^2, 1 mrad in the corners).
    EXPECT_GT(turn.ray_rms_rad, 0.01 * turn.angle_rad);
    EXPECT_LT(turn.ray_rms_rad, 0.05 * turn.angle_rad);

    std::vector<Vec3> points{{0, 0, 500}, {100, -50, 400}};
    const std::vector<Vec3> before = points;
    fpp::calib::turn_points(turn, points);
    for (std::size_t k = 0; k < points.size(); ++k) {
        EXPECT_NEAR(std::hypot(points[k][0], points[k][1], points[k][2]),
                    std::hypot(before[k][0], before[k][1], before[k][2]), 1e-9);
    }
    EXPECT_NEAR(points[0][0], 500 * turn.Q[2], 1e-9);
    EXPECT_NEAR(points[0][2], 500 * turn.Q[8], 1e-9);
}

TEST(FrameTurn, TooFewRaysOrABadStepAreRefused) {
    StereoCalibration c = pinhole_calibration();
    EXPECT_THROW(camera_frame_turn(c, c.camera, 0), std::invalid_argument);
    c.camera_size = {1, 1};
    EXPECT_THROW(camera_frame_turn(c, c.camera), std::invalid_argument);
}

} // namespace
