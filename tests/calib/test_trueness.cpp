// The predicted trueness (fpp/calib/trueness.hpp) against the truth: the
// calibration's covariance carried to lengths must say how far a length
// measured with it is from the true one, over many sessions.

#include "fpp/calib/simulated_rig.hpp"
#include "fpp/calib/stereo_calibrate.hpp"
#include "fpp/calib/trueness.hpp"
#include "stereo_observations.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace {

using namespace fpp;

struct Observed {
    double predicted_mm = 0, error_mm = 0;
    double z() const { return error_mm / predicted_mm; }
};

// Error of a length along depth (or across) at the session's middle depth,
// measured with `c` on `rig`, against the predicted sigma.
Observed observe_length(const sim::Rig& rig, const calib::StereoCalibration& c, bool along_depth) {
    const calib::StereoCalibration truth = calib::calibration_from_rig(rig);
    const calib::LengthSigma& m = c.trueness.middle();
    const double half = c.trueness.length_mm / 2;
    const Vec3 a = along_depth ? Vec3{0, 0, m.depth_mm - half} : Vec3{-half, 0, m.depth_mm};
    const Vec3 b = along_depth ? Vec3{0, 0, m.depth_mm + half} : Vec3{half, 0, m.depth_mm};
    return {along_depth ? m.along_depth_mm : m.across_mm,
            calib::measured_length(truth, c, a, b) - c.trueness.length_mm};
}

// Over 20 sessions (other pose draws and other noise, 12 poses with 0.05 px
// of corner noise, the default camera-first procedure with both correction
// grids): the observed depth-scale error within 2 predicted sigma in at
// least 90 % of them, and the predictions neither too small nor too large
// (the RMS of error / sigma near 1: a sigma ten times too large would pass
// the first rule alone).
TEST(Trueness, PredictedSigmaHoldsTheObservedLengthErrorsOverTwentySessions) {
    const sim::Rig rig = test::model_rig();
    constexpr int kSessions = 20;
    std::vector<Observed> depth, across;
    for (int session = 1; session <= kSessions; ++session) {
        sim::SessionOptions options;
        options.poses = 12;
        options.seed = std::uint64_t(session);
        const auto obs = test::observe(rig, options, 0.05, std::uint32_t(100 + session));
        const calib::StereoResult r =
            calib::stereo_calibrate(obs, rig.camera_size, rig.projector_size);
        ASSERT_TRUE(r.calibration.trueness.known()) << "session " << session;
        depth.push_back(observe_length(rig, r.calibration, true));
        across.push_back(observe_length(rig, r.calibration, false));
    }
    const auto judge = [&](const std::vector<Observed>& v, const char* what) {
        int within = 0;
        double sum_z2 = 0;
        std::vector<double> z;
        for (const Observed& o : v) {
            ASSERT_GT(o.predicted_mm, 0) << what;
            within += std::fabs(o.z()) <= 2;
            sum_z2 += o.z() * o.z();
            z.push_back(o.z());
        }
        std::sort(z.begin(), z.end());
        const double rms_z = std::sqrt(sum_z2 / double(v.size()));
        std::printf(
            "%s: %d of %zu within 2 sigma; error / sigma: min %.2f, median %.2f, max "
            "%.2f, RMS %.2f; sigma %.4f ... %.4f mm\n",
            what, within, v.size(), z.front(), z[z.size() / 2], z.back(), rms_z,
            std::min_element(v.begin(), v.end(),
                             [](auto& a, auto& b) { return a.predicted_mm < b.predicted_mm; })
                ->predicted_mm,
            std::max_element(v.begin(), v.end(), [](auto& a, auto& b) {
                return a.predicted_mm < b.predicted_mm;
            })->predicted_mm);
        EXPECT_GE(within, 18) << what;
        EXPECT_GT(rms_z, 0.5) << what << ": the predicted sigma is too large to mean anything";
        EXPECT_LT(rms_z, 1.6) << what;
    };
    judge(depth, "150 mm along depth");
    judge(across, "150 mm across");
}

// The figures are where a report needs them: in the calibration, at the
// session's depths, and the map over the whole image.
TEST(Trueness, PredictionCoversTheSessionsDepthsAndTheImage) {
    const sim::Rig rig = test::model_rig();
    const auto obs = test::observe(rig, 12, 0.05);
    const calib::StereoResult r = calib::stereo_calibrate(obs, rig.camera_size, rig.projector_size);
    const calib::Trueness& t = r.calibration.trueness;
    ASSERT_TRUE(t.known());
    EXPECT_EQ(t.length_mm, 150);
    EXPECT_LT(t.at[0].depth_mm, t.at[1].depth_mm);
    EXPECT_LT(t.at[1].depth_mm, t.at[2].depth_mm);
    EXPECT_GT(t.at[0].depth_mm, 300);
    EXPECT_LT(t.at[2].depth_mm, 700);
    // A depth scale error is the same share of a length at every depth;
    // what the near and far ends add to it is second order.
    for (const calib::LengthSigma& at : t.at) {
        EXPECT_GT(at.along_depth_mm, 0.5 * t.middle().along_depth_mm);
        EXPECT_LT(at.along_depth_mm, 2 * t.middle().along_depth_mm);
        EXPECT_GT(at.across_mm, 0);
        EXPECT_LT(at.across_mm, at.along_depth_mm); // the lateral scale is pinned by the board
    }
    const calib::TruenessMap& map = r.trueness_map;
    ASSERT_GT(map.cell_px, 0);
    EXPECT_EQ(map.sigma_mm.width(), (rig.camera_size.width + map.cell_px - 1) / map.cell_px);
    int finite = 0;
    for (std::size_t k = 0; k < map.sigma_mm.pixel_count(); ++k)
        finite += std::isfinite(map.sigma_mm.data()[k]) && map.sigma_mm.data()[k] > 0;
    EXPECT_EQ(finite, int(map.sigma_mm.pixel_count()));
    const std::string text = calib::trueness_summary(t);
    EXPECT_NE(text.find("along depth"), std::string::npos) << text;
    EXPECT_NE(text.find("ppm"), std::string::npos) << text;
}

} // namespace
