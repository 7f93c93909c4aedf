// The exposures of an HDR scan (fpp/scanner/exposure_plan.hpp): a white
// preview measured at the decoder's thresholds, fixed exposures checked
// against the camera's range, and the automatic search on a scene whose
// saturation is known at every exposure.
#include <gtest/gtest.h>

#include "fpp/error.hpp"
#include "fpp/scanner/exposure_plan.hpp"

#include <cstdint>
#include <string>
#include <vector>

using fpp::Frame;
using fpp::scanner::automatic_exposures;
using fpp::scanner::measure_preview;

namespace {

template <class T> Frame frame_of(const std::vector<T>& levels) {
    Frame f;
    f.bit_depth = sizeof(T) == 1 ? 8 : 16;
    fpp::Image<T> image(fpp::Size{static_cast<int>(levels.size()), 1}, 1, T{0});
    for (std::size_t i = 0; i < levels.size(); ++i)
        image.data()[i] = levels[i];
    if constexpr (sizeof(T) == 1)
        f.u8 = std::move(image);
    else
        f.u16 = std::move(image);
    return f;
}

// 100 pixels of reflectance 1..100: pixel i reads i * exposure / 1000 DN
// (8 bits, clipped), so it saturates (>= 254) from 254000 / i us on.
Frame ramp_scene(double exposure_us) {
    std::vector<std::uint8_t> levels;
    for (int i = 1; i <= 100; ++i)
        levels.push_back(static_cast<std::uint8_t>(std::min(255.0, i * exposure_us / 1000.0)));
    return frame_of(levels);
}

fpp::scanner::HdrConfig automatic(double max_saturated, int passes, double ratio) {
    fpp::scanner::HdrConfig h;
    h.automatic = true;
    h.max_saturated = max_saturated;
    h.passes = passes;
    h.ratio = ratio;
    return h;
}

} // namespace

TEST(ExposurePlan, PreviewCountsLitAndSaturatedAtTheDecodersThresholds) {
    // 8 bits: lit from 5 DN (2 % of 255, truncated), saturated from 254.
    const auto e8 = measure_preview(frame_of<std::uint8_t>({0, 4, 5, 100, 253, 254, 255}));
    EXPECT_EQ(e8.lit, 5u);
    EXPECT_EQ(e8.saturated, 2u);
    EXPECT_DOUBLE_EQ(e8.saturated_fraction(), 0.4);
    // 16 bits: lit from 1310, saturated from 65469.
    const auto e16 = measure_preview(frame_of<std::uint16_t>({1309, 1310, 65468, 65469, 65535}));
    EXPECT_EQ(e16.lit, 4u);
    EXPECT_EQ(e16.saturated, 2u);
    // Nothing lit: no fraction to divide by.
    EXPECT_EQ(measure_preview(frame_of<std::uint8_t>({0, 1, 2})).saturated_fraction(), 0.0);
}

TEST(ExposurePlan, FixedExposuresOutsideTheCameraRangeAreRefusedNamingTheEntry) {
    fpp::scanner::BoardConfig board;
    board.file = "board.yaml";
    board.hdr.emplace();
    board.hdr->exposures_us = {100, 5, 2000};
    try {
        check_hdr_exposures(board, {10, 1e6});
        FAIL() << "5 us passed a camera of 10..1000000 us";
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), "hdr.exposures_us[1]");
        EXPECT_NE(std::string(e.what()).find(
                      "5.0 us is outside the camera's exposure range 10.0..1e+06 us"),
                  std::string::npos)
            << e.what();
    }
    board.hdr->exposures_us = {10, 1e6};
    EXPECT_NO_THROW(check_hdr_exposures(board, {10, 1e6}));
    board.hdr.reset();
    EXPECT_NO_THROW(check_hdr_exposures(board, {10, 1e6}));
}

TEST(ExposurePlan, AutomaticSearchStepsDownToTheAllowedSaturationThenAddsShorterPasses) {
    std::vector<double> previews;
    const auto preview = [&](double e) {
        previews.push_back(e);
        return ramp_scene(e);
    };
    // 8000 us saturates 69 % of the lit pixels, 4000 us 37 % (<= 40 %):
    // the longest pass; 2000 us saturates none, so the search ends there.
    EXPECT_EQ(automatic_exposures(automatic(0.40, 3, 2), 8000, {10, 1e6}, preview),
              (std::vector<double>{4000, 2000}));
    EXPECT_EQ(previews, (std::vector<double>{8000, 4000, 2000}));
    // At most `passes`: the last pass needs no preview.
    previews.clear();
    EXPECT_EQ(automatic_exposures(automatic(0.40, 2, 2), 8000, {10, 1e6}, preview),
              (std::vector<double>{4000, 2000}));
    EXPECT_EQ(previews, (std::vector<double>{8000, 4000}));
    // Not below the camera's minimum: 2000 us is not allowed, one pass.
    EXPECT_EQ(automatic_exposures(automatic(0.40, 3, 2), 8000, {3000, 1e6}, preview),
              (std::vector<double>{4000}));
    // A start above the camera's maximum is clamped to it.
    previews.clear();
    EXPECT_EQ(automatic_exposures(automatic(0.40, 3, 2), 1e7, {10, 4000}, preview),
              (std::vector<double>{4000, 2000}));
    EXPECT_EQ(previews.front(), 4000);
}
