// A verification figure against its maximum permissible error
// (fpp/calib/mpe_plot.hpp): the scale holding every value and the band,
// the band shaded (-mpe .. +mpe for a signed figure, 0 .. mpe otherwise),
// markers inside it blue and outside it red, no verdict without an MPE. The
// pixels are read where the layout puts them (820 x 480, plot 700 x 350 at
// (90, 60), value k of n at x = 90 + 700 (k + 1/2) / n).

#include "fpp/calib/mpe_plot.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace {

const cv::Vec3b kWhite(255, 255, 255), kBand(200, 235, 200), kInside(150, 90, 30),
    kOutside(40, 40, 210);

// The plot's row of value v on the scale lo .. hi.
int y_of(double v, double lo, double hi) {
    return 60 + static_cast<int>(std::lround((hi - v) / (hi - lo) * 350));
}

cv::Mat plot(const std::vector<double>& values, std::optional<double> mpe, bool signed_figure) {
    std::vector<std::string> labels;
    for (std::size_t k = 0; k < values.size(); ++k)
        labels.push_back(std::to_string(k + 1));
    return fpp::calib::mpe_plot(values, labels, mpe, signed_figure, "measurement", "error (mm)",
                                "sphere spacing");
}

TEST(MpePlot, ASignedFiguresBandAndItsMarkers) {
    // The largest |value|, 0.08, times 1.15 rounds up to a scale of +-0.1.
    const cv::Mat image = plot({0.02, -0.05, 0.08}, 0.06, true);
    ASSERT_EQ(image.type(), CV_8UC3);
    ASSERT_EQ(image.cols, 820);
    ASSERT_EQ(image.rows, 480);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.02, -0.1, 0.1), 207), kInside);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(-0.05, -0.1, 0.1), 440), kInside);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.08, -0.1, 0.1), 673), kOutside);
    // The band from -0.06 to +0.06, white outside it.
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.055, -0.1, 0.1), 300), kBand);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(-0.055, -0.1, 0.1), 300), kBand);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.065, -0.1, 0.1), 300), kWhite);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(-0.065, -0.1, 0.1), 300), kWhite);
}

TEST(MpePlot, AnUnsignedFiguresBandStartsAtZero) {
    // 0.03 x 1.15 rounds up to a scale of 0 .. 0.05.
    const cv::Mat image = plot({0.01, 0.03}, 0.02, false);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.01, 0, 0.05), 265), kInside); // 90 + 700 / 4
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.03, 0, 0.05), 615), kOutside);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.015, 0, 0.05), 440), kBand);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.028, 0, 0.05), 440), kWhite);
}

TEST(MpePlot, WithoutAnMpeNoBandAndNoVerdict) {
    const cv::Mat image = plot({0.02, -0.05, 0.08}, std::nullopt, true);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.08, -0.1, 0.1), 673), kInside); // not red
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.055, -0.1, 0.1), 300), kWhite);
}

TEST(MpePlot, TheScaleHoldsTheBandWhenTheValuesAreSmaller) {
    // Values of at most 0.01 against an MPE of 0.2: a scale of +-0.5
    // (0.2 x 1.15 rounded up), the band's edge inside the plot.
    const cv::Mat image = plot({0.01, -0.01}, 0.2, true);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.19, -0.5, 0.5), 300), kBand);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.21, -0.5, 0.5), 300), kWhite);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.01, -0.5, 0.5), 265), kInside);
}

TEST(MpePlot, ValuesThatAreNotNumbersAreLeftOut) {
    // No marker for NaN; the others where three values put them.
    const cv::Mat image = plot({0.02, std::nan(""), 0.08}, 0.06, true);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.02, -0.1, 0.1), 207), kInside);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.08, -0.1, 0.1), 673), kOutside);
    EXPECT_EQ(image.at<cv::Vec3b>(y_of(0.0, -0.1, 0.1) - 30, 440), kBand); // no stem at x = 440
}

} // namespace
