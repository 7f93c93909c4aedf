// A simulated person following a session's pose advice (stereo_calibrate's
// next poses, session_check.hpp) until the default target is met, judged
// against the truth: a long run (tens of calibrations).

#include "fpp/calib/simulated_rig.hpp"
#include "fpp/calib/stereo_calibrate.hpp"
#include "fpp/calib/trueness.hpp"
#include "stereo_observations.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

namespace {

using namespace fpp;

constexpr double kNoisePx = 0.05;

double depth_sigma(const calib::StereoResult& r) {
    return r.calibration.trueness.middle().along_depth_mm;
}

// A person starts with 3 hurried poses and then follows the advice (placing
// the board within a few degrees and millimetres of it) until the check
// says enough: at most 30 poses, and the calibration's ball bar (150 mm)
// in the seven VDI/VDE 2634-2 positions then within 0.015 mm of the truth
// with no correction.
TEST(SessionAdvice, ASimulatedPersonFollowingTheAdviceReachesTheTarget) {
    const sim::Rig rig = test::model_rig();
    sim::SessionOptions start;
    start.poses = 3;
    start.seed = 7;
    start.max_tilt_deg = 10;
    std::vector<calib::PoseObservations> obs = test::observe(rig, start, kNoisePx, 7);
    std::mt19937 rng(23);
    std::normal_distribution<double> degrees(0, 2), mm(0, 5);
    calib::StereoOptions options;
    options.suggest_next_poses = 1;
    // The model rig's lens has no defect: the stiff grid cross-validation
    // would choose, without its cost at every pose.
    options.camera_grid_smoothness = 1e4;
    calib::StereoResult r;
    constexpr double kTarget = 0.015;
    while (true) {
        r = calib::stereo_calibrate(obs, rig.camera_size, rig.projector_size, options);
        ASSERT_TRUE(r.calibration.trueness.known()) << obs.size() << " poses";
        std::printf("%2zu poses: sigma along depth %.4f mm\n", obs.size(), depth_sigma(r));
        if (depth_sigma(r) <= kTarget || obs.size() >= 30)
            break;
        ASSERT_FALSE(r.next_poses.empty());
        const calib::PoseSuggestion& next = r.next_poses.front();
        std::printf("    next: %s\n", next.words().c_str());
        // Placed by hand: a small turn about a random axis and a shift.
        const double a = degrees(rng) * std::numbers::pi / 180;
        const Mat3 turn{1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a)};
        const Mat3 R = mul(turn, next.R);
        const Vec3 t{next.t[0] + mm(rng), next.t[1] + mm(rng), next.t[2] + mm(rng)};
        obs.push_back(test::observe_pose(rig, R, t, obs.front().board, kNoisePx, rng,
                                         "pose-" + std::to_string(obs.size() + 1)));
    }
    EXPECT_LE(depth_sigma(r), kTarget);
    EXPECT_LE(obs.size(), 30u);

    // The seven positions of a 150 mm ball bar: the three axes, and four
    // diagonals of the volume reaching in depth; centred at the middle depth.
    const calib::StereoCalibration truth = calib::calibration_from_rig(rig);
    const double z = r.calibration.trueness.middle().depth_mm, h = 75;
    const double d = h / std::sqrt(3.0), e = h / std::sqrt(2.0);
    const Vec3 directions[7] = {{h, 0, 0},  {0, h, 0}, {0, 0, h}, {d, d, d},
                                {-d, d, d}, {e, 0, e}, {0, e, e}};
    for (const Vec3& v : directions) {
        const double sd = calib::measured_length(truth, r.calibration, {-v[0], -v[1], z - v[2]},
                                                 {v[0], v[1], z + v[2]}) -
                          150;
        std::printf("ball bar along (%.0f, %.0f, %.0f): SD %+.4f mm\n", v[0], v[1], v[2], sd);
        EXPECT_LE(std::fabs(sd), 0.015);
    }
}

} // namespace
