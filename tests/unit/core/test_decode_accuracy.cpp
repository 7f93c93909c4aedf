#include "fpp/decode_accuracy.hpp"
#include "fpp/error.hpp"
#include "fpp/false_colour.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST(DecodeAccuracy, SeparatesUnwrappingErrorsFromNoise) {
    fpp::Image<float> truth(10, 10, 2, 0.0f);
    fpp::Image<float> decoded(10, 10, 1, 0.0f);
    for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 10; ++x) {
            truth.at(x, y, 0) = float(100 + x);
            truth.at(x, y, 1) = float(50 + y);
            decoded.at(x, y) = truth.at(x, y, 0) + ((x + y) % 2 ? 0.1f : -0.1f);
        }
    decoded.at(3, 3) = truth.at(3, 3, 0) + 20.0f; // one period off: an unwrapping error
    decoded.at(4, 4) = kNaN;                      // not decoded
    truth.at(5, 5, 0) = kNaN;                     // decoded where no light reaches
    const auto a = fpp::compare_to_truth(decoded, truth, 0, 20.0);
    EXPECT_EQ(a.truth_valid, 99u);
    EXPECT_EQ(a.decoded_valid, 99u);
    EXPECT_EQ(a.compared, 98u);
    EXPECT_EQ(a.false_valid, 1u);
    EXPECT_EQ(a.unwrap_errors, 1u);
    EXPECT_NEAR(a.rms_px, 0.1, 1e-5); // float values near 100 carry ~8e-6 of rounding
    EXPECT_NEAR(a.max_abs_px, 0.1, 1e-5);
    EXPECT_NEAR(a.coverage(), 98.0 / 99.0, 1e-12);
}

TEST(DecodeAccuracy, RejectsMismatchedImages) {
    fpp::Image<float> truth(10, 10, 2);
    fpp::Image<float> decoded(9, 10, 1);
    EXPECT_THROW(fpp::compare_to_truth(decoded, truth, 0, 20.0), fpp::InputError);
    fpp::Image<float> same(10, 10, 1);
    EXPECT_THROW(fpp::compare_to_truth(same, truth, 2, 20.0), fpp::InputError);
}

TEST(FalseColour, NaNIsBlackAndRampEndsDiffer) {
    fpp::Image<float> v(3, 1, 1);
    v.at(0, 0) = 0.0f;
    v.at(1, 0) = kNaN;
    v.at(2, 0) = 1.0f;
    const auto rgb = fpp::false_colour(v, 0.0f, 1.0f);
    ASSERT_EQ(rgb.channels(), 3);
    EXPECT_EQ(rgb.at(1, 0, 0) + rgb.at(1, 0, 1) + rgb.at(1, 0, 2), 0);
    // Low end is blue-dominant, high end red-dominant.
    EXPECT_GT(rgb.at(0, 0, 2), rgb.at(0, 0, 0));
    EXPECT_GT(rgb.at(2, 0, 0), rgb.at(2, 0, 2));
}

} // namespace
