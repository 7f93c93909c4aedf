// Where a calibration pose samples the board's bright flat parts
// (fpp/calib/board_samples.hpp), on a decode result written here: pixels
// that decoded with a modulation of at least a fraction of the pose's bright
// level (its 90th percentile), eroded away from every dropped pixel and the
// image's edge; the share kept; the dense samples on a grid; the options'
// and the inputs' refusals.

#include "fpp/calib/board_samples.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

using fpp::DecodeResult;
using fpp::Image;
using fpp::Vec2;
using fpp::calib::BrightBoardOptions;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// 40 x 30 pixels: columns 0 and 1 did not decode, columns 10..19 are a dark
// square (modulation 20), the rest bright (100 x `gain`); projector x = 2u +
// 0.5, y = 3v.
DecodeResult pose(float gain = 1) {
    DecodeResult r;
    r.camera = {40, 30};
    r.proj_x = Image<float>(r.camera);
    r.proj_y = Image<float>(r.camera);
    r.modulation = Image<float>(r.camera);
    for (int v = 0; v < 30; ++v)
        for (int u = 0; u < 40; ++u) {
            r.proj_x.at(u, v) = u < 2 ? kNaN : 2.0f * float(u) + 0.5f;
            r.proj_y.at(u, v) = 3.0f * float(v);
            r.modulation.at(u, v) = (u >= 10 && u < 20 ? 20.0f : 100.0f) * gain;
        }
    return r;
}

int count(const Image<std::uint8_t>& mask) {
    int n = 0;
    for (const std::uint8_t m : mask.storage())
        n += m ? 1 : 0;
    return n;
}

std::string refusal(const BrightBoardOptions& options) {
    try {
        options.validate();
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "valid";
}

TEST(BoardSamples, BrightDecodedPixelsWithoutErosion) {
    BrightBoardOptions options;
    options.erosion_px = 0;
    const Image<std::uint8_t> mask = fpp::calib::bright_board_mask(pose(), true, options);
    ASSERT_EQ(mask.size(), (fpp::Size{40, 30}));
    EXPECT_EQ(count(mask), (8 + 20) * 30); // columns 2..9 and 20..39
    EXPECT_EQ(mask.at(1, 5), 0);           // not decoded
    EXPECT_EQ(mask.at(2, 5), 1);
    EXPECT_EQ(mask.at(15, 5), 0); // dark: 20 < 0.5 x 100
    // Only relative levels count: the same mask at any exposure.
    EXPECT_EQ(fpp::calib::bright_board_mask(pose(7.5f), true, options).storage(), mask.storage());
    // A fraction above 0.2 of the bright level drops the dark square; below, keeps it.
    options.min_modulation_fraction = 0.19;
    EXPECT_EQ(count(fpp::calib::bright_board_mask(pose(), true, options)), 38 * 30);
}

TEST(BoardSamples, ErosionKeepsPixelsWhoseWholeWindowIsKept) {
    const Image<std::uint8_t> mask = fpp::calib::bright_board_mask(pose(), true); // 3 px
    // Columns 5..6 and 23..36, rows 3..26.
    EXPECT_EQ(count(mask), (2 + 14) * 24);
    EXPECT_EQ(mask.at(5, 3), 1);
    EXPECT_EQ(mask.at(4, 3), 0);
    EXPECT_EQ(mask.at(6, 26), 1);
    EXPECT_EQ(mask.at(6, 27), 0);
    EXPECT_EQ(mask.at(7, 10), 0);
    EXPECT_EQ(mask.at(23, 10), 1);
    EXPECT_EQ(mask.at(36, 10), 1);
    EXPECT_EQ(mask.at(37, 10), 0);
    // Of the 38 x 30 decoded pixels.
    EXPECT_DOUBLE_EQ(fpp::calib::bright_fraction(pose(), mask), 384.0 / 1140.0);
}

TEST(BoardSamples, DenseSamplesOnAGridOfTheKeptPixels) {
    const DecodeResult decoded = pose();
    const Image<std::uint8_t> mask = fpp::calib::bright_board_mask(decoded, true);
    std::vector<Vec2> camera, projector;
    fpp::calib::dense_projector_samples(decoded, mask, 4, camera, projector);
    // u in 2, 6, 10, ... kept at 6, 26, 30, 34; v in 2, 6, ... kept at 6 .. 26.
    ASSERT_EQ(camera.size(), 24u);
    ASSERT_EQ(projector.size(), 24u);
    EXPECT_EQ(camera[0], (Vec2{6, 6}));
    EXPECT_EQ(projector[0], (Vec2{12.5, 18}));
    EXPECT_EQ(camera[23], (Vec2{34, 26}));
    EXPECT_EQ(projector[23], (Vec2{68.5, 78}));
    // No projector rows, or no step: no samples (earlier ones cleared).
    DecodeResult x_only = decoded;
    x_only.proj_y = Image<float>();
    fpp::calib::dense_projector_samples(x_only, mask, 4, camera, projector);
    EXPECT_TRUE(camera.empty() && projector.empty());
    fpp::calib::dense_projector_samples(decoded, mask, 0, camera, projector);
    EXPECT_TRUE(camera.empty());
}

TEST(BoardSamples, NothingIsKeptWithoutModulationOrDecodedPixels) {
    DecodeResult no_modulation = pose();
    no_modulation.modulation = Image<float>();
    EXPECT_EQ(count(fpp::calib::bright_board_mask(no_modulation, true)), 0);
    DecodeResult nothing = pose();
    for (float& x : nothing.proj_x.storage())
        x = kNaN;
    const Image<std::uint8_t> mask = fpp::calib::bright_board_mask(nothing, false);
    EXPECT_EQ(count(mask), 0);
    EXPECT_EQ(fpp::calib::bright_fraction(nothing, mask), 0.0);
}

TEST(BoardSamples, RefusesBadOptionsAndAMissingProjectorRow) {
    EXPECT_EQ(refusal({}), "valid");
    EXPECT_EQ(refusal({0.0, 3}), "bright board option min_modulation_fraction: must be in (0, 1)");
    EXPECT_EQ(refusal({1.0, 3}), "bright board option min_modulation_fraction: must be in (0, 1)");
    EXPECT_EQ(refusal({0.5, -1}), "bright board option erosion_px: must be in [0, 50]");
    EXPECT_EQ(refusal({0.5, 51}), "bright board option erosion_px: must be in [0, 50]");
    EXPECT_THROW(fpp::calib::bright_board_mask(pose(), true, {0.5, 51}), std::invalid_argument);
    DecodeResult x_only = pose();
    x_only.proj_y = Image<float>();
    try {
        fpp::calib::bright_board_mask(x_only, true);
        FAIL() << "a mask needing y from a decode without y";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "bright board mask: the capture decodes no projector row");
    }
    EXPECT_EQ(count(fpp::calib::bright_board_mask(x_only, false)), (2 + 14) * 24);
}

} // namespace
