// Pattern generation against the formulas of firmware/core/formats/capture-set.md, written out
// again here independently of the implementation, plus hand-worked values.

#include "fpp/patterns.hpp"

#include "pattern_blocks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>

namespace {

constexpr double kPi = std::numbers::pi;

std::uint8_t level(double intensity) {
    return static_cast<std::uint8_t>(std::round(255.0 * intensity));
}

// Spec: I_k(p) = 1/2 + 1/2 cos(2 pi p / period + phase_offset + shift_sign 2 pi k / N).
double spec_phase(const fpp::PhaseBlock& b, int k, double p) {
    return 0.5 + 0.5 * std::cos(2.0 * kPi * p / b.period + b.phase_offset +
                                static_cast<double>(b.shift_sign) * 2.0 * kPi * k / b.steps);
}

long long gray_code(long long n) {
    return n ^ (n >> 1);
}

// Spec, plain: plane j white where bit (bits-1-j) of g(floor(p/period)) is 1.
bool spec_plain_bit(double period, int bits, int j, int p) {
    const auto n = static_cast<long long>(std::floor(p / period));
    return ((gray_code(n) >> (bits - 1 - j)) & 1) != 0;
}

// Spec, complementary: plane j of g(floor(2p/period)) on bits+1 bits, MSB first.
bool spec_complementary_bit(double period, int bits, int j, int p) {
    const auto n = static_cast<long long>(std::floor(2.0 * p / period));
    return ((gray_code(n) >> (bits - j)) & 1) != 0;
}

using fpp::test::gray;
using fpp::test::phase;

// Profile of an x-axis pattern (row 0), checking that every row equals it.
std::string row_bits(const fpp::Image<std::uint8_t>& image) {
    std::string s;
    for (int x = 0; x < image.width(); ++x)
        s += image.at(x, 0) == 255 ? '1' : image.at(x, 0) == 0 ? '0' : '?';
    return s;
}

} // namespace

TEST(Patterns, PhaseMatchesSpecFormulaBothSignsOffsetsAndAxes) {
    const fpp::Size projector{97, 61};
    for (const auto axis : {fpp::Axis::x, fpp::Axis::y}) {
        for (const int sign : {1, -1}) {
            for (const double offset : {0.0, -kPi, 0.7}) {
                for (const auto& [period, steps] :
                     {std::pair{20.0, 8}, std::pair{7.3, 3}, std::pair{71.25, 4}}) {
                    const auto b = phase(axis, period, steps, sign, offset);
                    for (int k = 0; k < steps; ++k) {
                        const auto image = fpp::render_pattern(b, k, projector);
                        ASSERT_EQ(image.size(), projector);
                        for (int y = 0; y < projector.height; ++y) {
                            for (int x = 0; x < projector.width; ++x) {
                                const double p = axis == fpp::Axis::x ? x : y;
                                ASSERT_EQ(image.at(x, y), level(spec_phase(b, k, p)))
                                    << "axis " << to_string(axis) << " sign " << sign << " offset "
                                    << offset << " period " << period << " k " << k << " at " << x
                                    << "," << y;
                            }
                        }
                        // pattern_intensity is the continuous formula, also between pixels.
                        for (const double p : {0.0, 3.25, 40.5}) {
                            const double x = axis == fpp::Axis::x ? p : 1.0;
                            const double y = axis == fpp::Axis::x ? 1.0 : p;
                            EXPECT_NEAR(fpp::pattern_intensity(b, k, x, y), spec_phase(b, k, p),
                                        1e-12);
                        }
                    }
                }
            }
        }
    }
}

TEST(Patterns, PhaseHandWorkedValues) {
    // Period 4, 4 steps, k = 0: crests (255) at p = 0, 4 and troughs (0) at p = 2, 6.
    // shift_sign +1, k = 1 adds pi/2: the crest moves to p = 3 (phase 2 pi * 3/4 + pi/2 = 2 pi).
    // shift_sign -1, k = 1 subtracts pi/2: the crest moves to p = 1.
    const auto plus = phase(fpp::Axis::x, 4.0, 4, 1, 0.0);
    const auto minus = phase(fpp::Axis::x, 4.0, 4, -1, 0.0);
    const auto f0 = fpp::render_pattern(plus, 0, {8, 1});
    const auto f1 = fpp::render_pattern(plus, 1, {8, 1});
    const auto g1 = fpp::render_pattern(minus, 1, {8, 1});
    EXPECT_EQ(f0.at(0, 0), 255);
    EXPECT_EQ(f0.at(4, 0), 255);
    EXPECT_EQ(f0.at(2, 0), 0);
    EXPECT_EQ(f0.at(6, 0), 0);
    EXPECT_EQ(f1.at(3, 0), 255);
    EXPECT_EQ(f1.at(7, 0), 255);
    EXPECT_EQ(f1.at(1, 0), 0);
    EXPECT_EQ(g1.at(1, 0), 255);
    EXPECT_EQ(g1.at(3, 0), 0);
    // phase_offset -pi (SLMaster's data) turns crests into troughs.
    const auto shifted = fpp::render_pattern(phase(fpp::Axis::x, 4.0, 4, 1, -kPi), 0, {8, 1});
    EXPECT_EQ(shifted.at(0, 0), 0);
    EXPECT_EQ(shifted.at(2, 0), 255);
}

TEST(Patterns, PlainGrayMatchesSpec) {
    const fpp::Size projector{200, 3};
    for (const double period : {20.0, 7.5, 60.0}) {
        const auto b = gray(fpp::Axis::x, period, 5, false, false);
        ASSERT_EQ(fpp::frame_count(b), 5);
        for (int j = 0; j < 5; ++j) {
            const auto image = fpp::render_pattern(b, j, projector);
            for (int y = 0; y < projector.height; ++y) {
                for (int x = 0; x < projector.width; ++x) {
                    ASSERT_EQ(image.at(x, y), spec_plain_bit(period, 5, j, x) ? 255 : 0)
                        << "period " << period << " plane " << j << " x " << x;
                }
            }
        }
    }
}

TEST(Patterns, PlainGrayHandWorkedPlanes) {
    // Period 2, 3 bits over 16 pixels: n = floor(p/2) = 0..7, g = 0,1,3,2,6,7,5,4.
    const auto b = gray(fpp::Axis::x, 2.0, 3, false, false);
    EXPECT_EQ(row_bits(fpp::render_pattern(b, 0, {16, 1})), "0000000011111111"); // MSB
    EXPECT_EQ(row_bits(fpp::render_pattern(b, 1, {16, 1})), "0000111111110000");
    EXPECT_EQ(row_bits(fpp::render_pattern(b, 2, {16, 1})), "0011110000111100"); // LSB
}

TEST(Patterns, ComplementaryGrayMatchesSpecAndExtendsThePlainCode) {
    const fpp::Size projector{250, 2};
    for (const double period : {20.0, 9.0}) {
        const auto plain = gray(fpp::Axis::x, period, 5, false, false);
        const auto comp = gray(fpp::Axis::x, period, 5, true, false);
        ASSERT_EQ(fpp::frame_count(comp), 6);
        for (int j = 0; j < 6; ++j) {
            const auto image = fpp::render_pattern(comp, j, projector);
            for (int x = 0; x < projector.width; ++x) {
                ASSERT_EQ(image.at(x, 1), spec_complementary_bit(period, 5, j, x) ? 255 : 0)
                    << "plane " << j << " x " << x;
            }
            // The first `bits` planes are the plain code of floor(p/period).
            if (j < 5) {
                EXPECT_EQ(image.storage(), fpp::render_pattern(plain, j, projector).storage()) << j;
            }
        }
    }
    // Hand-worked: period 4, 2 bits, 16 pixels: floor(2p/4) = 0..7 (each twice),
    // g = 0,1,3,2,6,7,5,4, on 3 bits.
    const auto hand = gray(fpp::Axis::x, 4.0, 2, true, false);
    EXPECT_EQ(row_bits(fpp::render_pattern(hand, 0, {16, 1})), "0000000011111111");
    EXPECT_EQ(row_bits(fpp::render_pattern(hand, 1, {16, 1})), "0000111111110000");
    EXPECT_EQ(row_bits(fpp::render_pattern(hand, 2, {16, 1})),
              "0011110000111100"); // half-period plane
}

TEST(Patterns, InverseGrayInterleavesEachPlaneWithItsInverse) {
    const fpp::Size projector{130, 4};
    for (const bool complementary : {false, true}) {
        const auto base = gray(fpp::Axis::y, 10.0, 4, complementary, false);
        const auto inv = gray(fpp::Axis::y, 10.0, 4, complementary, true);
        const int planes = complementary ? 5 : 4;
        ASSERT_EQ(fpp::frame_count(inv), 2 * planes);
        const fpp::Size tall{4, 130};
        for (int j = 0; j < planes; ++j) {
            const auto plane = fpp::render_pattern(base, j, tall);
            const auto shown = fpp::render_pattern(inv, 2 * j, tall);
            const auto inverse = fpp::render_pattern(inv, 2 * j + 1, tall);
            EXPECT_EQ(shown.storage(), plane.storage()) << j;
            for (std::size_t i = 0; i < plane.storage().size(); ++i) {
                ASSERT_EQ(inverse.storage()[i], 255 - plane.storage()[i]) << j << " " << i;
            }
        }
    }
    (void)projector;
}

TEST(Patterns, GrayAlongYVariesWithRowsOnly) {
    const auto b = gray(fpp::Axis::y, 3.0, 4, false, false);
    const auto image = fpp::render_pattern(b, 3, {7, 40});
    for (int y = 0; y < 40; ++y) {
        for (int x = 0; x < 7; ++x) {
            ASSERT_EQ(image.at(x, y), spec_plain_bit(3.0, 4, 3, y) ? 255 : 0) << x << "," << y;
        }
    }
}

TEST(Patterns, CenterlineLightsExactlyThePixelsWithinHalfTheWidth) {
    auto lit = [](double position, double width, int extent) {
        fpp::CenterlineBlock b;
        b.axis = fpp::Axis::x;
        b.position = position;
        b.width = width;
        return row_bits(fpp::render_pattern(b, 0, {extent, 2}));
    };
    EXPECT_EQ(lit(5.0, 1.0, 10), "0000010000");
    EXPECT_EQ(lit(5.0, 2.0, 10), "0000111000"); // |p - 5| <= 1 includes 4 and 6
    EXPECT_EQ(lit(4.5, 2.0, 10), "0000110000");
    EXPECT_EQ(lit(4.5, 0.5, 10), "0000000000"); // between pixels: nothing lit
    EXPECT_EQ(lit(0.0, 3.0, 10), "1100000000");

    fpp::CenterlineBlock y;
    y.axis = fpp::Axis::y;
    y.position = 3.0;
    y.width = 1.0;
    const auto image = fpp::render_pattern(y, 0, {5, 6});
    for (int r = 0; r < 6; ++r) {
        for (int c = 0; c < 5; ++c)
            EXPECT_EQ(image.at(c, r), r == 3 ? 255 : 0);
    }
    EXPECT_EQ(fpp::pattern_intensity(y, 0, 100.0, 3.4), 1.0);
    EXPECT_EQ(fpp::pattern_intensity(y, 0, 100.0, 3.6), 0.0);
}

TEST(Patterns, WhiteAndBlackAreUniform) {
    const auto white = fpp::render_pattern(fpp::WhiteBlock{}, 0, {33, 21});
    const auto black = fpp::render_pattern(fpp::BlackBlock{}, 0, {33, 21});
    for (auto v : white.storage())
        ASSERT_EQ(v, 255);
    for (auto v : black.storage())
        ASSERT_EQ(v, 0);
    EXPECT_EQ(fpp::pattern_intensity(fpp::WhiteBlock{}, 0, 3, 4), 1.0);
    EXPECT_EQ(fpp::pattern_intensity(fpp::BlackBlock{}, 0, 3, 4), 0.0);
}

TEST(Patterns, FrameOutOfRangeAndInvalidBlocksThrow) {
    const auto b = phase(fpp::Axis::x, 20.0, 8, 1, 0.0);
    EXPECT_THROW(fpp::render_pattern(b, 8, {10, 10}), std::out_of_range);
    EXPECT_THROW(fpp::render_pattern(b, -1, {10, 10}), std::out_of_range);
    EXPECT_THROW(fpp::pattern_intensity(fpp::WhiteBlock{}, 1, 0, 0), std::out_of_range);
    EXPECT_THROW(fpp::render_pattern(phase(fpp::Axis::x, 0.0, 8, 1, 0.0), 0, {10, 10}),
                 std::invalid_argument);
    EXPECT_THROW(fpp::render_pattern(gray(fpp::Axis::x, 20.0, 0, false, false), 0, {10, 10}),
                 std::invalid_argument);
    EXPECT_THROW(fpp::render_pattern(b, 0, {0, 10}), std::invalid_argument);
}

TEST(Patterns, GammaLutIdentityAndPrecompensation) {
    const auto identity = fpp::GammaLut::identity();
    for (int v = 0; v < 256; ++v)
        EXPECT_EQ(identity.level[std::size_t(v)], v);
    // gamma 1 is the identity.
    EXPECT_EQ(fpp::GammaLut::precompensate(1.0).level, identity.level);

    for (const double gamma : {2.2, 1.8, 2.6, 0.8}) {
        SCOPED_TRACE(gamma);
        const auto lut = fpp::GammaLut::precompensate(gamma);
        EXPECT_EQ(lut.level[0], 0);
        EXPECT_EQ(lut.level[255], 255);
        auto emitted = [gamma](int level) { return 255.0 * std::pow(level / 255.0, gamma); };
        for (int v = 0; v < 256; ++v) {
            const int l = lut.level[std::size_t(v)];
            if (v > 0) {
                EXPECT_GE(l, lut.level[std::size_t(v - 1)]) << v; // monotonic
            }
            // The projector then emits the wanted intensity within one level...
            EXPECT_LE(std::abs(std::round(emitted(l)) - v), 1.0) << v;
            // ...and no other drive level would come closer.
            const double error = std::abs(emitted(l) - v);
            if (l > 0) {
                EXPECT_LE(error, std::abs(emitted(l - 1) - v) + 1e-9) << v;
            }
            if (l < 255) {
                EXPECT_LE(error, std::abs(emitted(l + 1) - v) + 1e-9) << v;
            }
        }
    }
    // Dark values need much higher drive levels under gamma 2.2.
    EXPECT_EQ(fpp::GammaLut::precompensate(2.2).level[128], 186);
    EXPECT_THROW(fpp::GammaLut::precompensate(0.0), std::invalid_argument);
    EXPECT_THROW(fpp::GammaLut::precompensate(std::nan("")), std::invalid_argument);
}

TEST(Patterns, RenderAppliesTheLutToTheRoundedLevel) {
    const auto lut = fpp::GammaLut::precompensate(2.2);
    const auto b = phase(fpp::Axis::x, 13.0, 5, -1, 0.3);
    for (int k = 0; k < 5; ++k) {
        const auto plain = fpp::render_pattern(b, k, {50, 2});
        const auto mapped = fpp::render_pattern(b, k, {50, 2}, &lut);
        for (std::size_t i = 0; i < plain.storage().size(); ++i) {
            ASSERT_EQ(mapped.storage()[i], lut.level[plain.storage()[i]]);
        }
    }
}

TEST(Patterns, RenderSequenceGivesEveryFrameInCaptureOrder) {
    const fpp::Sequence seq = {fpp::WhiteBlock{}, fpp::BlackBlock{},
                               phase(fpp::Axis::x, 20.0, 3, 1, 0.0),
                               gray(fpp::Axis::x, 20.0, 3, true, false)};
    const fpp::Size projector{64, 8};
    const auto frames = fpp::render_sequence(seq, projector);
    ASSERT_EQ(frames.size(), 1u + 1u + 3u + 4u);
    EXPECT_EQ(frames[0].storage(), fpp::render_pattern(seq[0], 0, projector).storage());
    EXPECT_EQ(frames[1].storage(), fpp::render_pattern(seq[1], 0, projector).storage());
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(frames[std::size_t(2 + k)].storage(),
                  fpp::render_pattern(seq[2], k, projector).storage());
    }
    for (int j = 0; j < 4; ++j) {
        EXPECT_EQ(frames[std::size_t(5 + j)].storage(),
                  fpp::render_pattern(seq[3], j, projector).storage());
    }
}
