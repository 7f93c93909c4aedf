// False colour for people to look at (fpp/false_colour.hpp): the ramp's
// colours, its clamping, lightness rising from the blue end to the yellow,
// and the map of an image (its range, NaN and an empty range black).

#include "fpp/false_colour.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace {

using Rgb = std::array<int, 3>;

Rgb ramp(float t) {
    std::uint8_t rgb[3] = {1, 2, 3};
    fpp::ramp_colour(t, rgb);
    return {rgb[0], rgb[1], rgb[2]};
}

Rgb pixel(const fpp::Image<std::uint8_t>& image, int x, int y = 0) {
    return {image.at(x, y, 0), image.at(x, y, 1), image.at(x, y, 2)};
}

TEST(FalseColour, RampColours) {
    // The control colours (deep blue-violet, cyan-green, green, yellow) and
    // points between them, each channel rounded from the ramp's fractions.
    EXPECT_EQ(ramp(0.0f), (Rgb{46, 13, 115}));
    EXPECT_EQ(ramp(0.3f), (Rgb{19, 134, 210}));
    EXPECT_EQ(ramp(0.5f), (Rgb{51, 198, 147}));
    EXPECT_EQ(ramp(0.6f), (Rgb{89, 217, 89}));
    EXPECT_EQ(ramp(0.7f), (Rgb{170, 217, 64}));
    EXPECT_EQ(ramp(0.8f), (Rgb{250, 217, 38}));
    EXPECT_EQ(ramp(1.0f)[0], 217); // red at the top
    EXPECT_EQ(ramp(1.0f)[1], 38);
}

TEST(FalseColour, RampClampsOutsideZeroToOne) {
    EXPECT_EQ(ramp(-1.0f), ramp(0.0f));
    EXPECT_EQ(ramp(2.0f), ramp(1.0f));
}

TEST(FalseColour, LightnessRisesFromTheBlueEndToTheYellow) {
    // Order reads at a glance: luma (Rec. 601) rises at every step up to the
    // yellow control colour.
    double previous = -1;
    for (int i = 0; i <= 16; ++i) {
        const Rgb c = ramp(0.05f * static_cast<float>(i));
        const double luma = 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2];
        EXPECT_GT(luma, previous) << "t = " << 0.05 * i;
        previous = luma;
    }
}

TEST(FalseColour, MapsTheRangeClampsOutsideItAndBlacksOutNaN) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float values[] = {10, 13, 15, 16, 18, 20, nan, 5, 25};
    fpp::Image<float> image(9, 2);
    for (int x = 0; x < 9; ++x) {
        image.at(x, 0) = values[x];
        image.at(x, 1) = values[8 - x];
    }
    const fpp::Image<std::uint8_t> out = fpp::false_colour(image, 10.0f, 20.0f);
    ASSERT_EQ(out.size(), image.size());
    ASSERT_EQ(out.channels(), 3);
    EXPECT_EQ(pixel(out, 0), ramp(0.0f));
    EXPECT_EQ(pixel(out, 1), (Rgb{19, 134, 210}));
    EXPECT_EQ(pixel(out, 2), (Rgb{51, 198, 147}));
    EXPECT_EQ(pixel(out, 3), (Rgb{89, 217, 89}));
    EXPECT_EQ(pixel(out, 4), (Rgb{250, 217, 38}));
    EXPECT_EQ(pixel(out, 5), ramp(1.0f));
    EXPECT_EQ(pixel(out, 6), (Rgb{0, 0, 0}));
    EXPECT_EQ(pixel(out, 7), ramp(0.0f));
    EXPECT_EQ(pixel(out, 8), ramp(1.0f));
    // The second row, reversed.
    EXPECT_EQ(pixel(out, 0, 1), ramp(1.0f));
    EXPECT_EQ(pixel(out, 2, 1), (Rgb{0, 0, 0}));
    EXPECT_EQ(pixel(out, 8, 1), ramp(0.0f));
}

TEST(FalseColour, AnEmptyRangeIsAllBlack) {
    fpp::Image<float> image(3, 3, 1, 7.0f);
    for (const auto& [lo, hi] : {std::array<float, 2>{7, 7}, std::array<float, 2>{8, 2}}) {
        const fpp::Image<std::uint8_t> out = fpp::false_colour(image, lo, hi);
        ASSERT_EQ(out.size(), image.size());
        for (const std::uint8_t v : out.storage())
            EXPECT_EQ(v, 0) << lo << ".." << hi;
    }
}

TEST(FalseColour, ReadsTheFirstChannelOfAMultiChannelImage) {
    fpp::Image<float> image(2, 1, 3, 100.0f); // other channels far outside the range
    image.at(0, 0, 0) = 0.0f;
    image.at(1, 0, 0) = 1.0f;
    const fpp::Image<std::uint8_t> out = fpp::false_colour(image, 0.0f, 1.0f);
    EXPECT_EQ(pixel(out, 0), ramp(0.0f));
    EXPECT_EQ(pixel(out, 1), ramp(1.0f));
}

} // namespace
