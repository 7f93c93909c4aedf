// A session that knows when it is enough (session_check.hpp and the pose
// advice of stereo_calibrate): the advice's predicted sigma against what the
// pose really does when it is added, and a simulated person following the
// advice until the default target is met, judged against the truth.

#include "fpp/calib/session_check.hpp"
#include "fpp/calib/stereo_calibrate.hpp"
#include "fpp/calib/trueness.hpp"
#include "stereo_observations.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

namespace {

using namespace fpp;

constexpr double kNoisePx = 0.05;

// A hurried start: boards nearly facing the camera.
std::vector<calib::PoseObservations> hurried(const sim::Rig& rig, int poses, std::uint64_t seed) {
    sim::SessionOptions options;
    options.poses = poses;
    options.seed = seed;
    options.max_tilt_deg = 10;
    return test::observe(rig, options, kNoisePx, std::uint32_t(seed));
}

double depth_sigma(const calib::StereoResult& r) {
    return r.calibration.trueness.middle().along_depth_mm;
}

TEST(SessionAdvice, TheSuggestedPoseDoesWhatItsPredictionSays) {
    const sim::Rig rig = test::model_rig();
    std::vector<calib::PoseObservations> obs = hurried(rig, 8, 5);
    calib::StereoOptions options;
    options.suggest_next_poses = 3;
    const calib::StereoResult before =
        calib::stereo_calibrate(obs, rig.camera_size, rig.projector_size, options);
    ASSERT_TRUE(before.calibration.trueness.known());
    ASSERT_EQ(before.next_poses.size(), 3u);
    const calib::PoseSuggestion& best = before.next_poses.front();
    std::printf("hurried 8 poses: sigma along depth %.4f mm; best next: %s -> %.4f mm\n",
                depth_sigma(before), best.words().c_str(), best.sigma_mm);
    EXPECT_LT(best.sigma_mm, 0.8 * depth_sigma(before));
    EXPECT_LE(best.sigma_mm, before.next_poses[1].sigma_mm);
    // What the hurried session lacks is tilt.
    EXPECT_GE(best.tilt_deg, 20);
    EXPECT_NE(best.words().find("tilt the board about"), std::string::npos) << best.words();

    // The person places the board there; the session is calibrated again.
    std::mt19937 rng(11);
    obs.push_back(
        test::observe_pose(rig, best.R, best.t, obs.front().board, kNoisePx, rng, "advised"));
    options.suggest_next_poses = 0;
    const calib::StereoResult after =
        calib::stereo_calibrate(obs, rig.camera_size, rig.projector_size, options);
    std::printf("with the advised pose: sigma along depth %.4f mm (predicted %.4f)\n",
                depth_sigma(after), best.sigma_mm);
    EXPECT_LT(depth_sigma(after), 1.3 * best.sigma_mm);
    EXPECT_GT(depth_sigma(after), 0.7 * best.sigma_mm);
}

TEST(SessionCheck, VerdictsAndTheirReasons) {
    const sim::Rig rig = test::model_rig();
    calib::SessionResult session;
    session.camera_size = rig.camera_size;
    session.projector_size = rig.projector_size;
    session.observations = hurried(rig, 8, 5);
    calib::StereoOptions options;
    options.suggest_next_poses = 2;
    session.stereo =
        calib::stereo_calibrate(session.observations, rig.camera_size, rig.projector_size, options);
    for (std::size_t i = 0; i < session.observations.size(); ++i) {
        session.poses.push_back({});
        session.calibrated.push_back(int(i));
    }
    const double sigma = depth_sigma(session.stereo);

    calib::SessionCheckOptions check;
    check.target_mm = 2 * sigma;
    calib::SessionCheck c = calib::check_session(session, check);
    EXPECT_EQ(c.verdict, calib::SessionVerdict::enough) << c.text();
    EXPECT_EQ(c.poses_used, 8);
    EXPECT_LE(c.max_tilt_deg, 10.5);
    EXPECT_GT(c.coverage_fraction, 0);
    EXPECT_LE(c.coverage_fraction, 1);
    EXPECT_EQ(c.text().find("Next pose"), std::string::npos) << c.text();

    check.target_mm = sigma / 2;
    c = calib::check_session(session, check);
    EXPECT_EQ(c.verdict, calib::SessionVerdict::not_yet) << c.text();
    EXPECT_NE(c.text().find("Next pose: tilt the board about"), std::string::npos) << c.text();
    EXPECT_NE(c.text().find("  or: "), std::string::npos) << c.text();

    check.target_mm = sigma / 40;
    c = calib::check_session(session, check);
    EXPECT_EQ(c.verdict, calib::SessionVerdict::too_weak) << c.text();
    EXPECT_NE(c.reason.find("every board faces the camera"), std::string::npos) << c.reason;

    const calib::SessionCheck none = calib::too_weak_session("only 2 of 2 poses are usable");
    EXPECT_EQ(none.verdict, calib::SessionVerdict::too_weak);
    EXPECT_NE(none.text().find("too weak: only 2 of 2 poses"), std::string::npos) << none.text();

    check.target_mm = -1;
    EXPECT_THROW(calib::check_session(session, check), std::invalid_argument);
}

// The verdicts' names (the report's and the CLI's), one each.
TEST(SessionCheck, VerdictNames) {
    EXPECT_STREQ(calib::to_string(calib::SessionVerdict::enough), "enough");
    EXPECT_STREQ(calib::to_string(calib::SessionVerdict::not_yet), "not yet");
    EXPECT_STREQ(calib::to_string(calib::SessionVerdict::too_weak), "too weak");
}

} // namespace
