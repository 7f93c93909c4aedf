// The depth scale a certified ball bar shows (fpp/calib/depth_scale.hpp):
// recovered from centre vectors scaled in depth, with its sigma; the
// refusals (too few positions, none reaching in depth, a position or a
// certificate that contradicts the others, a correction the calibration's
// trueness does not allow); the trueness written from the fit.

#include "fpp/calib/depth_scale.hpp"
#include "fpp/error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace {

using fpp::Vec3;
using fpp::calib::LengthObservation;

// A 150 mm bar along `axis`, its depth component scaled by `depth_scale`
// (what a scanner with that depth error measures), plus `extra` mm along
// the bar.
LengthObservation bar(const char* name, Vec3 axis, double depth_scale, double extra = 0) {
    const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    const double length = 150 + extra;
    return {name,
            Vec3{axis[0] / n * length, axis[1] / n * length, axis[2] / n * length * depth_scale}};
}

std::vector<LengthObservation> vdi_used(double depth_scale) {
    return {bar("p2", {0.87, 0, 0.5}, depth_scale), bar("p3", {-0.87, 0, 0.5}, depth_scale),
            bar("p5", {0.7, 0.5, 0.5}, depth_scale), bar("p7", {0.35, 1, -0.25}, depth_scale)};
}

fpp::calib::Trueness predicted(double depth_ppm) {
    fpp::calib::Trueness t;
    t.length_mm = 150;
    for (fpp::calib::LengthSigma& s : t.at) {
        s.along_depth_mm = depth_ppm * 1e-6 * 150;
        s.across_mm = 0.002;
    }
    return t;
}

std::string refusal(const std::vector<LengthObservation>& used, double certified,
                    const fpp::calib::Trueness& t) {
    try {
        const auto fit = fpp::calib::fit_depth_scale(used, certified, 0.001);
        fpp::calib::check_depth_scale_fit(fit, used, t, certified, 0.001, "bar.yaml", "c.yaml");
    } catch (const fpp::InputError& e) {
        return e.what();
    }
    return "";
}

TEST(DepthScale, RecoversTheDepthScaleOfTheLengths) {
    const double s = 1.0004; // 400 ppm too deep
    const auto fit = fpp::calib::fit_depth_scale(vdi_used(s), 150, 0.001);
    EXPECT_NEAR(fit.scale, 1 / s, 1e-9);
    EXPECT_EQ(fit.depth_positions, 3); // p7: |d_z| / |d| = 0.23
    EXPECT_NEAR(fit.scatter_mm, 0, 1e-9);
    // The certificate's 1 um alone, over the positions' depth reach.
    EXPECT_GT(fit.sigma, 5e-6);
    EXPECT_LT(fit.sigma, 5e-5);
    EXPECT_NO_THROW(fpp::calib::check_depth_scale_fit(fit, vdi_used(s), predicted(200), 150, 0.001,
                                                      "bar.yaml", "c.yaml"));
    const auto t = fpp::calib::trueness_from_fit(predicted(200), fit, 150);
    EXPECT_NEAR(t.middle().along_depth_mm, fit.sigma * 150, 1e-12);
    EXPECT_EQ(t.middle().across_mm, 0.002);
}

TEST(DepthScale, ACertificateOneMillimetreOffIsRefused) {
    const std::string why = refusal(vdi_used(1), 149, predicted(200));
    EXPECT_NE(why.find("refused as inconsistent, never corrected"), std::string::npos) << why;
    EXPECT_NE(why.find("bar.yaml"), std::string::npos) << why;
}

TEST(DepthScale, APositionDisagreeingWithTheOthersIsRefused) {
    std::vector<LengthObservation> used = vdi_used(1.0002);
    used[1] = bar("p3", {-0.87, 0, 0.5}, 1.0002, 0.08);
    const std::string why = refusal(used, 150, predicted(200));
    EXPECT_NE(why.find("refused as inconsistent"), std::string::npos) << why;
    EXPECT_NE(why.find("p3"), std::string::npos) << why;
}

TEST(DepthScale, ACorrectionBeyondThePredictedTruenessIsRefused) {
    // 3000 ppm where the calibration predicts 100 ppm: 5 sigma is 533 ppm.
    const std::string why = refusal(vdi_used(1.003), 150, predicted(100));
    EXPECT_NE(why.find("beyond the"), std::string::npos) << why;
    EXPECT_NE(why.find("c.yaml"), std::string::npos) << why;
}

TEST(DepthScale, PositionsAcrossTheImageOnlyOrTooFewAreRefused) {
    const std::vector<LengthObservation> across = {bar("a", {1, 0, 0}, 1.001),
                                                   bar("b", {0.6, 0.8, 0.05}, 1.001),
                                                   bar("c", {0.87, 0, 0.5}, 1.001)};
    try {
        (void)fpp::calib::fit_depth_scale(across, 150, 0.001);
        FAIL() << "fitted from one position reaching in depth";
    } catch (const fpp::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cannot be seen from lengths across"),
                  std::string::npos)
            << e.what();
    }
    EXPECT_THROW((void)fpp::calib::fit_depth_scale({bar("a", {0.87, 0, 0.5}, 1)}, 150, 0.001),
                 fpp::InputError);
}

} // namespace
