// The host tool's report figures (fpp/calib/plots.hpp): the numbers they
// print and their limits, the colour maps, and the figures' layout.

#include "fpp/calib/plots.hpp"

#include "fpp/false_colour.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using fpp::Image;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST(Plots, FixedTextPrintsDigitsOrADashForNoValue) {
    EXPECT_EQ(fpp::calib::fixed_text(0.123456, 3), "0.123");
    EXPECT_EQ(fpp::calib::fixed_text(-2.5, 0), "-2");
    EXPECT_EQ(fpp::calib::fixed_text(1234.5, 2), "1234.50");
    EXPECT_EQ(fpp::calib::fixed_text(std::nan(""), 3), "-");
    EXPECT_EQ(fpp::calib::fixed_text(std::numeric_limits<double>::infinity(), 3), "-");
}

TEST(Plots, NiceCeilingsAreOneTwoOrFiveTimesAPowerOfTen) {
    EXPECT_DOUBLE_EQ(fpp::calib::nice_ceil(0.001), 0.001);
    EXPECT_DOUBLE_EQ(fpp::calib::nice_ceil(0.0011), 0.002);
    EXPECT_DOUBLE_EQ(fpp::calib::nice_ceil(42), 50.0);
    EXPECT_DOUBLE_EQ(fpp::calib::nice_ceil(50), 50.0);
    EXPECT_DOUBLE_EQ(fpp::calib::nice_ceil(51), 100.0);
    // Nothing to round: 1.
    EXPECT_EQ(fpp::calib::nice_ceil(0), 1.0);
    EXPECT_EQ(fpp::calib::nice_ceil(-3), 1.0);
    EXPECT_EQ(fpp::calib::nice_ceil(std::nan("")), 1.0);
}

TEST(Plots, SymmetricLimitIgnoresNonFiniteValuesAndFallsBackOnZeros) {
    const double inf = std::numeric_limits<double>::infinity();
    const std::vector<double> values = {0.3, -0.7, std::nan(""), inf, 0.1};
    // The largest magnitude of the finite ones (quantile 1), rounded up.
    EXPECT_DOUBLE_EQ(fpp::calib::symmetric_limit(values, 1.0), 1.0);
    // The median magnitude, 0.3, rounded up.
    EXPECT_DOUBLE_EQ(fpp::calib::symmetric_limit(values, 0.5), 0.5);
    EXPECT_EQ(fpp::calib::symmetric_limit(std::vector<double>{0, 0, -0.0}, 0.99, 0.25), 0.25);
    EXPECT_EQ(fpp::calib::symmetric_limit(std::vector<double>{std::nan("")}, 0.99, 0.25), 0.25);
}

TEST(Plots, DivergingColoursAreTheRdBuAnchorsInBgr) {
    EXPECT_EQ(fpp::calib::diverging_colour(-1), cv::Vec3b(97, 48, 5));
    EXPECT_EQ(fpp::calib::diverging_colour(-0.5), cv::Vec3b(195, 147, 67));
    EXPECT_EQ(fpp::calib::diverging_colour(0), cv::Vec3b(247, 247, 247));
    EXPECT_EQ(fpp::calib::diverging_colour(0.5), cv::Vec3b(77, 96, 214));
    EXPECT_EQ(fpp::calib::diverging_colour(1), cv::Vec3b(31, 0, 103));
    // Half-way between white and the light red anchor.
    EXPECT_EQ(fpp::calib::diverging_colour(0.25), cv::Vec3b(162, 172, 231));
    EXPECT_EQ(fpp::calib::diverging_colour(std::nan("")), cv::Vec3b(247, 247, 247));
    EXPECT_EQ(fpp::calib::diverging_colour(-7), cv::Vec3b(97, 48, 5));
}

TEST(Plots, SeriesColoursCycleThroughFive) {
    EXPECT_EQ(fpp::calib::series_colour(0), cv::Scalar(40, 40, 200));
    EXPECT_EQ(fpp::calib::series_colour(1), cv::Scalar(180, 90, 30));
    EXPECT_NE(fpp::calib::series_colour(0), fpp::calib::series_colour(4));
    EXPECT_EQ(fpp::calib::series_colour(5), fpp::calib::series_colour(0));
    EXPECT_EQ(fpp::calib::series_colour(12), fpp::calib::series_colour(2));
}

TEST(Plots, MapFigureEnlargesACoarseMapByWholePixels) {
    Image<float> cells(4, 2, 1, 0.0f);
    cells.at(3, 1) = 1.0f;
    cells.at(0, 1) = kNaN;
    const cv::Mat figure = fpp::calib::map_figure(cells, 0.0f, 1.0f, "cells");
    // 400 / 4 = 100 px per cell, below a 30 px title band; a colour bar beside.
    EXPECT_EQ(figure.type(), CV_8UC3);
    EXPECT_EQ(figure.cols, 400 + 90 + 24);
    EXPECT_EQ(figure.rows, 200 + 30 + 10);
    std::uint8_t low[3], high[3];
    fpp::ramp_colour(0.0f, low);
    fpp::ramp_colour(1.0f, high);
    EXPECT_EQ(figure.at<cv::Vec3b>(30 + 50, 50), cv::Vec3b(low[2], low[1], low[0]));
    EXPECT_EQ(figure.at<cv::Vec3b>(30 + 150, 350), cv::Vec3b(high[2], high[1], high[0]));
    EXPECT_EQ(figure.at<cv::Vec3b>(30 + 150, 50), cv::Vec3b(0, 0, 0)); // no value: black
}

TEST(Plots, SignedMapFigureRefusesAnEmptyOrColourImage) {
    const auto message = [](const Image<float>& values) -> std::string {
        try {
            (void)fpp::calib::signed_map_figure(values, 1.0, "map");
        } catch (const std::invalid_argument& e) {
            return e.what();
        }
        return "accepted";
    };
    EXPECT_EQ(message(Image<float>()), "signed_map_figure: 1-channel, non-empty image expected");
    EXPECT_EQ(message(Image<float>(4, 4, 3)),
              "signed_map_figure: 1-channel, non-empty image expected");
    EXPECT_EQ(message(Image<float>(4, 4, 1)), "accepted");
}

TEST(Plots, NumbersAndColours) {
    EXPECT_DOUBLE_EQ(fpp::calib::nice_ceil(0.13), 0.2);
    EXPECT_DOUBLE_EQ(fpp::calib::nice_ceil(0.2), 0.2);
    EXPECT_DOUBLE_EQ(fpp::calib::nice_ceil(3.1), 5.0);
    EXPECT_DOUBLE_EQ(fpp::calib::nice_ceil(7), 10.0);
    std::vector<double> values(1000);
    for (std::size_t i = 0; i < values.size(); ++i)
        values[i] = (i % 2 ? 1.0 : -1.0) * 0.0001 * double(i); // |v| up to 0.0999
    values[3] = 50;                                            // one spike
    EXPECT_DOUBLE_EQ(fpp::calib::symmetric_limit(values, 0.99), 0.1);
    EXPECT_DOUBLE_EQ(fpp::calib::symmetric_limit(std::vector<double>{}, 0.99, 0.5), 0.5);
    const cv::Vec3b white = fpp::calib::diverging_colour(0);
    EXPECT_GT(white[0], 240);
    EXPECT_GT(white[2], 240);
    const cv::Vec3b red = fpp::calib::diverging_colour(1), blue = fpp::calib::diverging_colour(-1);
    EXPECT_GT(red[2], red[0]);                       // BGR: more red than blue
    EXPECT_GT(blue[0], blue[2]);                     // more blue than red
    EXPECT_EQ(fpp::calib::diverging_colour(5), red); // clamped
}

TEST(Plots, MapAndHistogramFigures) {
    Image<float> values(40, 30, 1, 0.0f);
    values.at(0, 0) = kNaN;
    values.at(39, 29) = 0.2f;
    const cv::Mat map = fpp::calib::signed_map_figure(values, 0.2, "test map");
    // Enlarged to at least 480 px wide, plus the colour bar panel.
    EXPECT_GE(map.cols, 480 + 100);
    EXPECT_EQ(map.type(), CV_8UC3);
    // The map's pixels: 12x enlargement, drawn at (10, 40).
    const cv::Vec3b nan_pixel = map.at<cv::Vec3b>(40 + 5, 10 + 5);
    EXPECT_EQ(nan_pixel, cv::Vec3b(90, 90, 90));
    const cv::Vec3b top = map.at<cv::Vec3b>(40 + 29 * 12 + 5, 10 + 39 * 12 + 5);
    EXPECT_EQ(top, fpp::calib::diverging_colour(1));

    const std::vector<double> a = {-0.1, 0.0, 0.05, 0.3}, b = {0.01, 0.02};
    const cv::Mat h = fpp::calib::histogram_figure({{"SV", a}, {"hybrid", b}}, -0.2, 0.2,
                                                   "error (mm)", "two series");
    EXPECT_EQ(h.type(), CV_8UC3);
    EXPECT_GT(h.cols, 400);
}

} // namespace
