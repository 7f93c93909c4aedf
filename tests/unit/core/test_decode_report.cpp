// The decode report (fpp/decode_report.hpp) and the diagnosis of failed
// decodes (fpp/decode_diagnosis.hpp), on captures built here from the spec's
// pattern formulas (fpp::pattern_intensity) through a simple camera model:
// camera pixel (x, y) sees projector pixel (8 + 1.9 x, 5 + 1.6 y); the left
// three quarters of the view are a lit surface (20 + 180 I DN in 8 bit), the
// right quarter dark background (3 DN); Gaussian read noise of 1.5 DN.

#include "fpp/decode_diagnosis.hpp"
#include "fpp/decode_report.hpp"
#include "fpp/error.hpp"
#include "fpp/patterns.hpp"
#include "fpp/sequences.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using fpp::CaptureSet;
using fpp::DecodeResult;
using fpp::Sequence;
using fpp::Size;

constexpr Size kCamera{160, 120};
constexpr Size kProjector{320, 200};
constexpr int kLitColumns = 120; // x < 120 lit, the rest dark background

struct Model {
    int bit_depth = 8;
    double scale = 1.0;  // DN multiplier (16: 12-bit samples in a 16-bit frame)
    double noise = 1.5;  // DN before scaling
    double gain = 180.0; // DN of the lit surface under full projector light, over its 20 DN
};

// Frames of `rendered` (the sequence the projector showed) seen by the camera.
std::vector<fpp::Frame> camera_frames(const Sequence& rendered, const Model& model) {
    std::mt19937 rng(16);
    std::normal_distribution<double> noise(0.0, model.noise);
    std::vector<fpp::Frame> frames;
    for (const auto& block : rendered)
        for (int k = 0; k < fpp::frame_count(block); ++k) {
            fpp::Frame f;
            f.bit_depth = model.bit_depth;
            if (model.bit_depth == 8)
                f.u8 = fpp::Image<std::uint8_t>(kCamera);
            else
                f.u16 = fpp::Image<std::uint16_t>(kCamera);
            const double top = model.bit_depth == 8 ? 255.0 : 65535.0;
            for (int y = 0; y < kCamera.height; ++y)
                for (int x = 0; x < kCamera.width; ++x) {
                    const double u = 8.0 + 1.9 * x, v = 5.0 + 1.6 * y;
                    const double light =
                        x < kLitColumns ? 20.0 + model.gain * fpp::pattern_intensity(block, k, u, v)
                                        : 3.0;
                    const double dn =
                        std::clamp(std::round((light + noise(rng)) * model.scale), 0.0, top);
                    if (model.bit_depth == 8)
                        f.u8.at(x, y) = static_cast<std::uint8_t>(dn);
                    else
                        f.u16.at(x, y) = static_cast<std::uint16_t>(dn);
                }
            frames.push_back(std::move(f));
        }
    return frames;
}

CaptureSet capture_of(const Sequence& declared, std::vector<fpp::Frame> frames) {
    CaptureSet set;
    set.folder = "synthetic";
    set.manifest.camera = kCamera;
    set.manifest.projector = kProjector;
    for (std::size_t i = 0; i < frames.size(); ++i)
        set.manifest.frames.push_back(std::to_string(i) + ".png");
    set.manifest.sequence = declared;
    set.frames = std::move(frames);
    return set;
}

struct Outcome {
    DecodeResult result;
    fpp::DecodeStatistics stats;
    fpp::DecodeDiagnosis diagnosis;
};

Outcome decode_and_diagnose(const CaptureSet& set) {
    Outcome o;
    o.result = fpp::decode(set);
    o.stats = fpp::decode_statistics(o.result, fpp::frames_full_scale(set));
    o.diagnosis = fpp::diagnose_decode(set, o.result, o.stats, {});
    return o;
}

// The lit region of the model is 120 x 120 pixels, the dark one 40 x 120.
constexpr std::size_t kLitPixels = 120 * 120;
constexpr std::size_t kDarkPixels = 40 * 120;

const fpp::DecodeTrial* named(const fpp::DecodeDiagnosis& d) {
    return d.best_trial < 0 ? nullptr : &d.trials[static_cast<std::size_t>(d.best_trial)];
}

TEST(DecodeStatistics, CleanCaptureLitPixelsAllDecodeAndTheFloorComesFromTheDarkPixels) {
    const Sequence sequence = fpp::standard_sequence("heterodyne-x", kProjector);
    const Outcome o = decode_and_diagnose(capture_of(sequence, camera_frames(sequence, {})));
    const auto& s = o.stats;
    std::printf("heterodyne-x: lit %zu, decoded %zu, floor %.3f DN, dark sigma %.3f DN\n", s.lit,
                s.decoded, s.lit_floor, s.dark_sigma);
    EXPECT_EQ(s.pixels, kCamera.area());
    EXPECT_EQ(s.counted(), s.pixels);
    EXPECT_EQ(s.lit, kLitPixels);
    EXPECT_EQ(s.dark, kDarkPixels);
    EXPECT_EQ(s.decoded, kLitPixels);
    EXPECT_DOUBLE_EQ(s.coverage_of_lit(), 1.0);
    // Read noise 1.5 DN over 8 steps: the modulation of a dark pixel is
    // Rayleigh with sigma 1.5 sqrt(2 / 8) = 0.75 DN (within a histogram bin, 0.125 DN).
    EXPECT_TRUE(s.floor_from_dark_mode);
    EXPECT_NEAR(s.dark_sigma, 0.75, 0.13);
    EXPECT_NEAR(s.lit_floor, 5 * s.dark_sigma, 1e-9);
    EXPECT_FALSE(o.diagnosis.failed);
    EXPECT_TRUE(o.diagnosis.message.empty());
    EXPECT_TRUE(o.diagnosis.trials.empty()); // no trial decodes for a good capture
}

TEST(DecodeStatistics, EachPixelCountedOnceByThePrecedence) {
    // Hand-made result: modulation and flags chosen per pixel.
    DecodeResult r;
    r.camera = {10, 100};
    r.mask = fpp::Image<std::uint8_t>(r.camera, 1, 0);
    r.modulation = fpp::Image<float>(r.camera, 1, 50.0f);
    std::mt19937 rng(3);
    std::normal_distribution<double> noise(0.0, 0.6);
    // Rows 0..39: dark (Rayleigh modulation of scale 0.6 DN), no flag but low modulation.
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 10; ++x) {
            const double a = noise(rng), b = noise(rng);
            r.modulation.at(x, y) = static_cast<float>(std::hypot(a, b));
            r.mask.at(x, y) = fpp::kDecodeLowModulation;
        }
    // Row 40: dark but saturated (all frames clipped: no modulation): saturated.
    for (int x = 0; x < 10; ++x) {
        r.modulation.at(x, 40) = 0.0f;
        r.mask.at(x, 40) = fpp::kDecodeSaturated | fpp::kDecodeLowModulation;
    }
    const std::uint8_t rows[][2] = {
        {41, fpp::kDecodeLowModulation | fpp::kDecodeUnwrapInconsistent},
        {42, fpp::kDecodeUnwrapInconsistent | fpp::kDecodeOutOfRange},
        {43, fpp::kDecodeOutOfRange},
        {44, fpp::kDecodeOutOfRange | fpp::kDecodeNoCue},
        {45, fpp::kDecodeNoCue},
        {46, 0}};
    for (const auto& [row, flags] : rows)
        for (int x = 0; x < 10; ++x)
            r.mask.at(x, row) = flags;
    for (int y = 47; y < 100; ++y)
        for (int x = 0; x < 10; ++x)
            r.mask.at(x, y) = fpp::kDecodeValid;
    // A decoded pixel below the floor still counts as lit and decoded.
    r.modulation.at(0, 99) = 0.1f;

    const fpp::DecodeStatistics s = fpp::decode_statistics(r, 255.0);
    EXPECT_TRUE(s.floor_from_dark_mode);
    EXPECT_GT(s.lit_floor, 2.0);
    EXPECT_LT(s.lit_floor, 4.5);
    EXPECT_EQ(s.dark, 400u);
    EXPECT_EQ(s.saturated, 10u);
    EXPECT_EQ(s.low_modulation, 10u);
    EXPECT_EQ(s.unwrap_inconsistent, 10u);
    EXPECT_EQ(s.out_of_range, 20u);
    EXPECT_EQ(s.no_cue, 10u);
    EXPECT_EQ(s.other, 10u);
    EXPECT_EQ(s.decoded, 530u);
    EXPECT_EQ(s.lit, 600u);
    EXPECT_EQ(s.counted(), 1000u);
    EXPECT_NEAR(s.coverage_of_lit(), 530.0 / 600.0, 1e-12);
}

TEST(DecodeStatistics, WithoutDarkPixelsTheFloorIsOnePercentOfFullScale) {
    DecodeResult r;
    r.camera = {50, 40};
    r.mask = fpp::Image<std::uint8_t>(r.camera, 1, fpp::kDecodeValid);
    r.modulation = fpp::Image<float>(r.camera, 1, 0.0f);
    for (std::size_t i = 0; i < r.modulation.pixel_count(); ++i)
        r.modulation.data()[i] = 30.0f + static_cast<float>(i % 40);
    const fpp::DecodeStatistics s = fpp::decode_statistics(r, 4095.0);
    EXPECT_FALSE(s.floor_from_dark_mode);
    EXPECT_DOUBLE_EQ(s.lit_floor, 40.95);
    EXPECT_EQ(s.lit, 2000u);
    EXPECT_EQ(s.decoded, 2000u);
    EXPECT_THROW(fpp::decode_statistics(r, 0.0), fpp::InputError);
    EXPECT_THROW(fpp::decode_statistics(DecodeResult{}, 255.0), fpp::InputError);
}

TEST(DecodeStatistics, FusedResultCountsPixelsLitInAnyPass) {
    DecodeResult bright, dim, fused;
    for (DecodeResult* r : {&bright, &dim, &fused}) {
        r->camera = {20, 20};
        r->mask = fpp::Image<std::uint8_t>(r->camera, 1, 0);
        r->modulation = fpp::Image<float>(r->camera, 1, 0.2f);
    }
    // Left half lit in the dim pass only (modulation 40 DN), not decoded anywhere.
    for (int y = 0; y < 20; ++y)
        for (int x = 0; x < 10; ++x) {
            dim.modulation.at(x, y) = 40.0f;
            dim.mask.at(x, y) = fpp::kDecodeUnwrapInconsistent;
            bright.mask.at(x, y) = fpp::kDecodeSaturated;
            fused.mask.at(x, y) = fpp::kDecodeUnwrapInconsistent | fpp::kDecodeSaturated;
            fused.modulation.at(x, y) = std::numeric_limits<float>::quiet_NaN();
        }
    // Top-right quarter decoded in the fusion.
    for (int y = 0; y < 10; ++y)
        for (int x = 10; x < 20; ++x)
            fused.mask.at(x, y) = fpp::kDecodeValid;
    const fpp::DecodeStatistics s = fpp::fused_decode_statistics(fused, {&bright, &dim}, 255.0);
    EXPECT_EQ(s.decoded, 100u);
    EXPECT_EQ(s.saturated, 200u);
    EXPECT_EQ(s.dark, 100u);
    EXPECT_EQ(s.lit, 300u);
    EXPECT_EQ(s.counted(), 400u);
}

TEST(DecodeDiagnosis, ReversedShiftIsNamed) {
    const Sequence declared = fpp::standard_sequence("heterodyne-x", kProjector);
    Sequence rendered = declared;
    std::get<fpp::PhaseBlock>(rendered[2]).shift_sign = -1;
    const Outcome o = decode_and_diagnose(capture_of(declared, camera_frames(rendered, {})));
    std::printf("reversed shift: %s\n", o.diagnosis.message.c_str());
    // The unwrapping checks accept about half the wrong coordinates.
    EXPECT_LT(o.stats.coverage_of_lit(), 0.6);
    EXPECT_TRUE(o.diagnosis.failed);
    const fpp::DecodeTrial* best = named(o.diagnosis);
    ASSERT_NE(best, nullptr) << o.diagnosis.message;
    // Flipping the sign and reversing the frames are the same fix for a
    // sequence without a phase offset; the sign is tried first.
    EXPECT_EQ(best->change, "shift_sign -1 in sequence[2]");
    EXPECT_GT(best->coverage_of_lit, 0.99);
    EXPECT_NE(o.diagnosis.message.find("With shift_sign -1 in sequence[2], 100 % of lit pixels "
                                       "decode instead of"),
              std::string::npos)
        << o.diagnosis.message;
}

TEST(DecodeDiagnosis, SwappedBlocksAreNamed) {
    const Sequence declared = fpp::standard_sequence("heterodyne-x", kProjector);
    auto frames = camera_frames(declared, {});
    for (std::size_t k = 0; k < 8; ++k)
        std::swap(frames[k], frames[8 + k]);
    const Outcome o = decode_and_diagnose(capture_of(declared, std::move(frames)));
    std::printf("swapped blocks: %s\n", o.diagnosis.message.c_str());
    EXPECT_LT(o.stats.coverage_of_lit(), 0.6);
    const fpp::DecodeTrial* best = named(o.diagnosis);
    ASSERT_NE(best, nullptr) << o.diagnosis.message;
    EXPECT_EQ(best->change, "the frames of sequence[0] and sequence[1] swapped");
    EXPECT_GT(best->coverage_of_lit, 0.99);
    EXPECT_TRUE(o.diagnosis.failed);
}

TEST(DecodeDiagnosis, TwelveBitFramesInSixteenBitsWithoutBitDepth) {
    // A dim 12-bit capture stored LSB-aligned in 16 bits, significant_bits
    // unknown: the modulation (about 800 DN) is below 2 % of 65535.
    const Sequence declared = fpp::standard_sequence("heterodyne-x", kProjector);
    Model twelve;
    twelve.bit_depth = 16;
    twelve.scale = 16.0;
    twelve.gain = 100.0;
    auto frames = camera_frames(declared, twelve);
    for (auto& f : frames)
        f.u16.at(0, 0) = 4095; // one specular highlight reaches the camera's top
    const Outcome o = decode_and_diagnose(capture_of(declared, std::move(frames)));
    std::printf("12-bit: %s\n", o.diagnosis.message.c_str());
    EXPECT_LT(o.stats.coverage_of_lit(), 0.10);
    EXPECT_EQ(o.stats.lit, kLitPixels - 1); // the highlight is constant: no modulation
    EXPECT_TRUE(o.diagnosis.failed);
    EXPECT_EQ(o.diagnosis.bits_in_use, 12);
    EXPECT_EQ(o.diagnosis.bits_declared, 16);
    const fpp::DecodeTrial* best = named(o.diagnosis);
    ASSERT_NE(best, nullptr) << o.diagnosis.message;
    EXPECT_EQ(best->change, "samples scaled to 16 bits");
    EXPECT_GT(best->coverage_of_lit, 0.99);
    EXPECT_NE(o.diagnosis.message.find("Declare `bit_depth: 12`"), std::string::npos)
        << o.diagnosis.message;
}

// A 16-bit capture that is simply too dark (5 of its 16 bits in use, the
// modulation about the noise): scaled to full depth it decodes no better,
// so the advice is to expose longer, not to declare a lower bit_depth.
TEST(DecodeDiagnosis, SixteenBitFramesTooDarkForTheirNoiseAreNotABitDepthMistake) {
    const Sequence declared = fpp::standard_sequence("heterodyne-x", kProjector);
    Model dark;
    dark.bit_depth = 16;
    dark.gain = 3.0;
    dark.noise = 2.0;
    const Outcome o = decode_and_diagnose(capture_of(declared, camera_frames(declared, dark)));
    std::printf("too dark: %s\n", o.diagnosis.message.c_str());
    EXPECT_TRUE(o.diagnosis.failed);
    EXPECT_LE(o.diagnosis.bits_in_use, 6);
    EXPECT_EQ(o.diagnosis.message.find("Declare `bit_depth"), std::string::npos)
        << o.diagnosis.message;
    EXPECT_NE(o.diagnosis.message.find("underexposed"), std::string::npos) << o.diagnosis.message;
}

TEST(DecodeDiagnosis, NothingLitSaysSo) {
    const Sequence declared = fpp::standard_sequence("heterodyne-x", kProjector);
    auto frames = camera_frames(declared, {});
    std::mt19937 rng(5);
    std::normal_distribution<double> noise(3.0, 1.5);
    for (auto& f : frames)
        for (auto& v : f.u8.storage())
            v = static_cast<std::uint8_t>(std::clamp(std::round(noise(rng)), 0.0, 255.0));
    const Outcome o = decode_and_diagnose(capture_of(declared, std::move(frames)));
    std::printf("nothing lit: %s\n", o.diagnosis.message.c_str());
    EXPECT_LT(o.stats.lit, kCamera.area() / 100);
    EXPECT_TRUE(o.diagnosis.failed);
    EXPECT_EQ(o.diagnosis.best_trial, -1);
    EXPECT_NE(o.diagnosis.message.find("Almost nothing is lit"), std::string::npos)
        << o.diagnosis.message;
}

} // namespace
