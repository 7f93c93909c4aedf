// Exposure fusion: per pixel, the passes that decoded it, weighted by their
// predicted coordinate noise.
#include "fpp/exposure_fusion.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace fpp {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A 4 x 1 pass decoding x only, every pixel valid at `x`, sigma `s`,
// modulation `b`.
ExposurePass pass(double exposure_us, float x, float s, float b) {
    ExposurePass p;
    p.exposure_us = exposure_us;
    p.decoded.camera = {4, 1};
    p.decoded.proj_x = Image<float>(4, 1, 1, x);
    p.decoded.modulation = Image<float>(4, 1, 1, b);
    p.decoded.mean = Image<float>(4, 1, 1, 2 * b);
    p.decoded.mask = Image<std::uint8_t>(4, 1, 1, kDecodeValid);
    p.decoded.method_x = "complementary-gray";
    p.sigma = Image<float>(4, 1, 1, s);
    return p;
}

void invalidate(ExposurePass& p, int x, std::uint8_t flags) {
    p.decoded.mask.at(x, 0) = flags;
    p.decoded.proj_x.at(x, 0) = kNaN;
    p.sigma.at(x, 0) = kNaN;
}

TEST(ExposureFusion, AgreeingPassesAreAveragedByInverseVariance) {
    std::vector<ExposurePass> passes{pass(8000, 100.0f, 0.1f, 40), pass(2000, 100.2f, 0.2f, 10)};
    DecodeResult out;
    Image<float> sigma;
    const FusionStats stats = fuse_exposures(passes, out, sigma);
    // Weights 100 and 25: (100 * 100 + 25 * 100.2) / 125.
    EXPECT_NEAR(out.proj_x.at(0, 0), 100.04f, 1e-4);
    EXPECT_NEAR(sigma.at(0, 0), 1.0 / std::sqrt(125.0), 1e-6);
    EXPECT_EQ(stats.averaged, 4u);
    EXPECT_EQ(stats.reference_pixels[0], 4u);
    EXPECT_EQ(stats.reference_pixels[1], 0u);
    EXPECT_TRUE(out.proj_y.empty());
    EXPECT_EQ(out.method_x, "complementary-gray");
    EXPECT_EQ(out.mask.at(0, 0), kDecodeValid);
}

TEST(ExposureFusion, ASaturatedPixelTakesTheShorterPassScaledToTheFirstExposure) {
    std::vector<ExposurePass> passes{pass(8000, 100.0f, 0.1f, 40), pass(2000, 100.05f, 0.3f, 60)};
    invalidate(passes[0], 1, kDecodeSaturated);
    DecodeResult out;
    Image<float> sigma;
    const FusionStats stats = fuse_exposures(passes, out, sigma);
    EXPECT_FLOAT_EQ(out.proj_x.at(1, 0), 100.05f);
    EXPECT_FLOAT_EQ(sigma.at(1, 0), 0.3f);
    // B at 8000 us: 60 DN at 2000 us times 4.
    EXPECT_FLOAT_EQ(out.modulation.at(1, 0), 240.0f);
    EXPECT_FLOAT_EQ(out.mean.at(1, 0), 480.0f);
    EXPECT_EQ(stats.reference_pixels[1], 1u);
    EXPECT_EQ(stats.averaged, 3u);
}

TEST(ExposureFusion, ADisagreeingPassIsLeftOut) {
    // A fringe order off by one period in the second pass.
    std::vector<ExposurePass> passes{pass(8000, 100.0f, 0.1f, 40), pass(2000, 100.0f, 0.2f, 10)};
    passes[1].decoded.proj_x.at(2, 0) = 120.0f;
    DecodeResult out;
    Image<float> sigma;
    const FusionStats stats = fuse_exposures(passes, out, sigma);
    EXPECT_FLOAT_EQ(out.proj_x.at(2, 0), 100.0f);
    EXPECT_FLOAT_EQ(sigma.at(2, 0), 0.1f);
    EXPECT_EQ(stats.disagreeing, 1u);
}

TEST(ExposureFusion, APixelSaturatedAtEveryExposureIsFlaggedAndNotDecoded) {
    std::vector<ExposurePass> passes{pass(8000, 100.0f, 0.1f, 40), pass(2000, 100.0f, 0.2f, 10)};
    invalidate(passes[0], 3, kDecodeSaturated);
    invalidate(passes[1], 3, kDecodeSaturated | kDecodeLowModulation);
    DecodeResult out;
    Image<float> sigma;
    const FusionStats stats = fuse_exposures(passes, out, sigma);
    EXPECT_TRUE(std::isnan(out.proj_x.at(3, 0)));
    EXPECT_TRUE(std::isnan(sigma.at(3, 0)));
    EXPECT_EQ(out.mask.at(3, 0), kDecodeSaturated | kDecodeLowModulation);
    EXPECT_EQ(stats.undecoded, 1u);
}

TEST(ExposureFusion, BadInputIsRefused) {
    DecodeResult out;
    Image<float> sigma;
    EXPECT_THROW(fuse_exposures({}, out, sigma), std::invalid_argument);
    std::vector<ExposurePass> passes{pass(8000, 1, 0.1f, 40), pass(2000, 1, 0.1f, 40)};
    passes[1].sigma = Image<float>(3, 1);
    EXPECT_THROW(fuse_exposures(passes, out, sigma), std::invalid_argument);
    passes[1] = pass(0, 1, 0.1f, 40);
    EXPECT_THROW(fuse_exposures(passes, out, sigma), std::invalid_argument);
    passes[1] = pass(2000, 1, 0.1f, 40);
    passes[1].decoded.proj_y = Image<float>(4, 1);
    EXPECT_THROW(fuse_exposures(passes, out, sigma), std::invalid_argument);
}

} // namespace
} // namespace fpp
