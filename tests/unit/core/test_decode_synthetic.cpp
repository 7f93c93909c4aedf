// Decoder tests on synthesised frames (tests/support/synthetic_decode.hpp):
// every unwrapping method recovers the projector coordinates, streaming and
// batch agree, the phase, mask, noise, Gray repair and centerline behaviour.
// The decoder's API contract is in test_decoder.cpp.

#include "synthetic_decode.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

namespace {

using namespace fpp::test::synthetic;

class MethodTest : public ::testing::TestWithParam<NamedSequence> {};

TEST_P(MethodTest, RecoversProjectorCoordinatesWithoutUnwrappingErrors) {
    const NamedSequence& ns = GetParam();
    const Synth synth = Synth::standard();
    const CaptureSet set = synth.capture(ns.sequence);
    const DecodeResult r = fpp::decode(set);
    EXPECT_EQ(r.method_x, ns.method_x);
    EXPECT_EQ(r.method_y, ns.method_y);
    ASSERT_EQ(r.camera, synth.camera);
    // RMS bound from 8-bit quantisation of patterns and frames (about 0.002
    // rad of phase); the direct method (one period over the projector) is
    // 40x coarser.
    for (int axis = 0; axis < 2; ++axis) {
        const double period = axis == 0 ? ns.period_x : ns.period_y;
        const Image<float>& decoded = axis == 0 ? r.proj_x : r.proj_y;
        if (period == 0) {
            EXPECT_TRUE(decoded.empty());
            continue;
        }
        const Accuracy a = accuracy(decoded, axis == 0 ? synth.truth_x : synth.truth_y, period);
        const double rms_limit = period >= 800 ? 0.4 : 0.03 * std::max(1.0, period / 20.0);
        EXPECT_EQ(a.unwrap_errors, 0u) << ns.name << " axis " << axis;
        EXPECT_LT(a.rms, rms_limit) << ns.name << " axis " << axis;
        EXPECT_GT(a.coverage(), 0.995) << ns.name << " axis " << axis;
    }
}

TEST_P(MethodTest, StreamingIsBitIdenticalToBatch) {
    const NamedSequence& ns = GetParam();
    const CaptureSet set = Synth::standard().capture(ns.sequence, 8, 2.0);
    DecodeOptions one_thread;
    one_thread.threads = 1;
    DecodeOptions three_threads;
    three_threads.threads = 3;
    const DecodeResult batch = fpp::decode(set, one_thread);
    const DecodeResult streamed = stream(set, three_threads);
    EXPECT_TRUE(same_bytes(batch.proj_x, streamed.proj_x));
    EXPECT_TRUE(same_bytes(batch.proj_y, streamed.proj_y));
    EXPECT_TRUE(same_bytes(batch.modulation, streamed.modulation));
    EXPECT_TRUE(same_bytes(batch.mean, streamed.mean));
    EXPECT_TRUE(same_bytes(batch.mask, streamed.mask));
    EXPECT_EQ(batch.method_x, streamed.method_x);
    EXPECT_EQ(batch.method_y, streamed.method_y);
    // Batch with several threads too.
    const DecodeResult batch3 = fpp::decode(set, three_threads);
    EXPECT_TRUE(same_bytes(batch.proj_x, batch3.proj_x));
    EXPECT_TRUE(same_bytes(batch.proj_y, batch3.proj_y));
    EXPECT_TRUE(same_bytes(batch.mask, batch3.mask));
}

INSTANTIATE_TEST_SUITE_P(Decode, MethodTest, ::testing::ValuesIn(method_sequences()),
                         [](const auto& param_info) {
                             std::string n = param_info.param.name;
                             std::replace(n.begin(), n.end(), '-', '_');
                             return n;
                         });

// Wrapped phase, modulation and mean against their analytic values: 16-bit
// frames computed per pixel (no pattern sampling), one period over the projector.
TEST(DecodePhase, WrappedPhaseModulationAndMeanAreExact) {
    const Size camera{160, 120};
    const Size projector{512, 384};
    for (int steps : {3, 4, 8, 12}) {
        for (int sign : {1, -1}) {
            for (double offset : {0.0, 1.3, -kPi}) {
                const fpp::PhaseBlock block = phase(Axis::x, 512, steps, sign, offset);
                CaptureSet set;
                set.manifest.camera = camera;
                set.manifest.projector = projector;
                set.manifest.sequence = {block};
                Image<float> p(camera), a(camera), b(camera);
                for (int y = 0; y < camera.height; ++y)
                    for (int x = 0; x < camera.width; ++x) {
                        p.at(x, y) = static_cast<float>(2.0 + x * 3.15 + y * 0.05);
                        a.at(x, y) = static_cast<float>(30000 + 40 * y);
                        b.at(x, y) = static_cast<float>(20000 - 30 * x);
                    }
                for (int k = 0; k < steps; ++k) {
                    Frame f;
                    f.bit_depth = 16;
                    f.u16 = Image<std::uint16_t>(camera);
                    for (int y = 0; y < camera.height; ++y)
                        for (int x = 0; x < camera.width; ++x) {
                            const double phi = 2 * kPi * double(p.at(x, y)) / 512.0 + offset +
                                               sign * 2 * kPi * k / steps;
                            f.u16.at(x, y) = static_cast<std::uint16_t>(std::lround(
                                double(a.at(x, y)) + double(b.at(x, y)) * std::cos(phi)));
                        }
                    set.frames.push_back(std::move(f));
                }
                const DecodeResult r = fpp::decode(set);
                EXPECT_EQ(r.method_x, "direct");
                double max_p = 0, max_a = 0, max_b = 0;
                for (int y = 0; y < camera.height; ++y)
                    for (int x = 0; x < camera.width; ++x) {
                        max_p = std::max(max_p,
                                         std::abs(double(r.proj_x.at(x, y)) - double(p.at(x, y))));
                        max_a =
                            std::max(max_a, std::abs(double(r.mean.at(x, y)) - double(a.at(x, y))));
                        max_b = std::max(
                            max_b, std::abs(double(r.modulation.at(x, y)) - double(b.at(x, y))));
                        EXPECT_EQ(r.mask.at(x, y), fpp::kDecodeValid);
                    }
                // Rounding to integers: theta error ~ 1e-5 rad = 1e-3 px at period 512.
                EXPECT_LT(max_p, 0.004)
                    << steps << " steps, sign " << sign << ", offset " << offset;
                EXPECT_LT(max_a, 0.6) << steps << " " << sign << " " << offset;
                EXPECT_LT(max_b, 1.0) << steps << " " << sign << " " << offset;
            }
        }
    }
}

// The direct method spans the projector: pixels at p in [-0.5, 0) stay there
// instead of wrapping to the far end.
TEST(DecodePhase, DirectWindowCoversTheProjectorEdges) {
    Synth s = Synth::standard();
    s.projector = {800, 600};
    for (int y = 0; y < s.camera.height; ++y)
        for (int x = 0; x < s.camera.width; ++x)
            s.truth_x.at(x, y) = static_cast<float>(-0.4 + x * (799.3 / 399.0));
    const CaptureSet set = s.capture({phase(Axis::x, 800, 12)}, 16);
    const DecodeResult r = fpp::decode(set);
    const Accuracy a = accuracy(r.proj_x, s.truth_x, 800, 0);
    EXPECT_EQ(a.unwrap_errors, 0u);
    EXPECT_LT(a.max_abs, 0.5);
}

TEST(DecodeNoise, ComplementaryGrayWithReadNoise) {
    const Synth synth = Synth::standard();
    const CaptureSet set = synth.capture(method_sequences()[0].sequence, 8, 1.5, 11);
    const DecodeResult r = fpp::decode(set);
    for (int axis = 0; axis < 2; ++axis) {
        const Accuracy a = accuracy(axis == 0 ? r.proj_x : r.proj_y,
                                    axis == 0 ? synth.truth_x : synth.truth_y, 20);
        EXPECT_EQ(a.unwrap_errors, 0u);
        EXPECT_LT(a.rms, 0.1);
        EXPECT_GT(a.coverage(), 0.995);
    }
}

TEST(DecodeMask, LowModulationAndSaturationAreFlagged) {
    Synth s = Synth::standard();
    // A dark patch (gain 2 DN: modulation about 1 DN < 0.02 * 255) and a
    // bright patch that clips at 255.
    for (int y = 50; y < 100; ++y)
        for (int x = 50; x < 100; ++x)
            s.gain.at(x, y) = 2.0f;
    for (int y = 200; y < 250; ++y)
        for (int x = 250; x < 300; ++x)
            s.gain.at(x, y) = 300.0f;
    const CaptureSet set = s.capture(method_sequences()[0].sequence);
    for (const DecodeResult& r : {fpp::decode(set), stream(set)}) {
        for (int y = 55; y < 95; ++y)
            for (int x = 55; x < 95; ++x) {
                EXPECT_TRUE(r.mask.at(x, y) & fpp::kDecodeLowModulation) << x << "," << y;
                EXPECT_FALSE(r.mask.at(x, y) & fpp::kDecodeValid);
                EXPECT_TRUE(std::isnan(r.proj_x.at(x, y)));
                EXPECT_TRUE(std::isnan(r.proj_y.at(x, y)));
            }
        for (int y = 200; y < 250; ++y)
            for (int x = 250; x < 300; ++x) {
                EXPECT_TRUE(r.mask.at(x, y) & fpp::kDecodeSaturated) << x << "," << y;
                EXPECT_TRUE(std::isnan(r.proj_x.at(x, y)));
            }
        EXPECT_EQ(r.mask.at(10, 10), fpp::kDecodeValid);
        EXPECT_TRUE(std::isfinite(r.proj_x.at(10, 10)));
    }
    // Raising the saturation level to full scale keeps the patch flagged (its
    // samples reach 255), lowering min_modulation to 0 clears the dark patch.
    DecodeOptions lenient;
    lenient.min_modulation = 0.0;
    const DecodeResult r = fpp::decode(set, lenient);
    EXPECT_FALSE(r.mask.at(70, 70) & fpp::kDecodeLowModulation);
}

// Gray frames that clip (a bright white stripe) still read as white: by
// default only the phase frames' saturation invalidates a pixel.
TEST(DecodeMask, SaturatedGrayFramesOnlyInvalidateWhenAsked) {
    Synth s = Synth::standard();
    const Sequence seq{phase(Axis::x, 20, 8), gray(Axis::x, 20, 6, true)};
    CaptureSet set = s.capture(seq);
    // Clip every gray plane's bright pixels in a patch.
    for (std::size_t f = 8; f < set.frames.size(); ++f)
        for (int y = 100; y < 150; ++y)
            for (int x = 100; x < 150; ++x) {
                std::uint8_t& v = set.frames[f].u8.at(x, y);
                if (v > 100)
                    v = 255;
            }
    const DecodeResult lenient = fpp::decode(set);
    const Accuracy a = accuracy(lenient.proj_x, s.truth_x, 20);
    EXPECT_EQ(a.unwrap_errors, 0u);
    EXPECT_GT(a.coverage(), 0.995);
    DecodeOptions strict;
    strict.saturation_in_binary_frames = true;
    const DecodeResult r = fpp::decode(set, strict);
    std::size_t flagged = 0;
    for (int y = 100; y < 150; ++y)
        for (int x = 100; x < 150; ++x)
            flagged += (r.mask.at(x, y) & fpp::kDecodeSaturated) != 0;
    EXPECT_GT(flagged, 1000u);
    EXPECT_TRUE(same_bytes(r.mask, stream(set, strict).mask));
}

// A coarse cue that disagrees with the fine phase by more than
// max_unwrap_disagreement (0.35 fine periods) flags the pixel.
TEST(DecodeMask, CoarseFineDisagreementIsFlagged) {
    const Synth s = Synth::standard();
    Synth shifted = s;
    for (int y = 0; y < s.camera.height; ++y)
        for (int x = 0; x < s.camera.width; ++x)
            shifted.truth_x.at(x, y) = static_cast<float>(double(s.truth_x.at(x, y)) + 8.0);
    const Sequence seq{phase(Axis::x, 20, 8), phase(Axis::x, 800, 8)};
    CaptureSet set = s.capture(seq);
    const CaptureSet moved = shifted.capture(seq);
    // Inside a patch the coarse frames see the map 8 px (0.4 fine periods) off.
    for (std::size_t f = 8; f < 16; ++f)
        for (int y = 50; y < 120; ++y)
            for (int x = 200; x < 300; ++x)
                set.frames[f].u8.at(x, y) = moved.frames[f].u8.at(x, y);
    const DecodeResult r = fpp::decode(set);
    std::size_t flagged = 0;
    for (int y = 55; y < 115; ++y)
        for (int x = 205; x < 295; ++x) {
            flagged += (r.mask.at(x, y) & fpp::kDecodeUnwrapInconsistent) != 0;
            EXPECT_FALSE(std::isfinite(r.proj_x.at(x, y)) &&
                         std::abs(r.proj_x.at(x, y) - s.truth_x.at(x, y)) > 10.0f);
        }
    EXPECT_GT(flagged, 60u * 90u * 9 / 10);
    // A looser limit accepts them (and they are right: 0.4 < 0.5).
    DecodeOptions loose;
    loose.max_unwrap_disagreement = 0.45;
    const DecodeResult l = fpp::decode(set, loose);
    EXPECT_EQ(accuracy(l.proj_x, s.truth_x, 20).unwrap_errors, 0u);
    EXPECT_FALSE(l.mask.at(250, 85) & fpp::kDecodeUnwrapInconsistent);
}

// Plain Gray repair near a step of the projector coordinate (an occlusion
// edge): pixels on either side must not take the other surface's fringe order.
TEST(DecodeGrayRepair, DoesNotCrossAnOcclusionEdge) {
    for (double jump : {20.0, -20.0, 13.7, 30.2, 40.0}) {
        Synth s = Synth::standard();
        for (int y = 0; y < s.camera.height; ++y)
            for (int x = 0; x < s.camera.width; ++x)
                if (x >= 200) {
                    const double moved = double(s.truth_x.at(x, y)) + jump;
                    // Outside the projector: no light, no truth.
                    s.truth_x.at(x, y) = moved <= 799 ? static_cast<float>(moved)
                                                      : std::numeric_limits<float>::quiet_NaN();
                }
        const Sequence seq{fpp::WhiteBlock{}, fpp::BlackBlock{}, phase(Axis::x, 20, 8),
                           gray(Axis::x, 20, 6, false)};
        const CaptureSet set = s.capture(seq, 8, 1.0, 3);
        const DecodeResult r = fpp::decode(set);
        const Accuracy a = accuracy(r.proj_x, s.truth_x, 20);
        EXPECT_EQ(a.unwrap_errors, 0u) << "jump " << jump;
        // Near the edge: no gross errors among valid pixels.
        std::size_t near_valid = 0;
        for (int y = 5; y < s.camera.height - 5; ++y)
            for (int x = 195; x < 205; ++x) {
                const float d = r.proj_x.at(x, y);
                if (!std::isfinite(d))
                    continue;
                ++near_valid;
                EXPECT_LT(std::abs(d - s.truth_x.at(x, y)), 1.0)
                    << x << "," << y << " jump " << jump;
            }
        EXPECT_GT(near_valid, 0u);
        // Away from the edge, nearly everything decodes.
        Image<float> far = s.truth_x;
        for (int y = 0; y < s.camera.height; ++y)
            for (int x = 190; x < 210; ++x)
                far.at(x, y) = std::numeric_limits<float>::quiet_NaN();
        EXPECT_GT(accuracy(r.proj_x, far, 20).coverage(), 0.99) << "jump " << jump;
    }
}

// Without the repair, plain Gray would be wrong at about the code edges; check
// the repair actually had something to do: with noise, the estimate near code
// edges is corrected rather than masked wholesale.
TEST(DecodeGrayRepair, PlainGrayWithNoiseHasNoUnwrappingErrors) {
    const Synth s = Synth::standard();
    const CaptureSet set = s.capture(method_sequences()[1].sequence, 8, 1.5, 5);
    const DecodeResult r = fpp::decode(set);
    const Accuracy a = accuracy(r.proj_x, s.truth_x, 20);
    EXPECT_EQ(a.unwrap_errors, 0u);
    EXPECT_GT(a.coverage(), 0.99);
    EXPECT_LT(a.rms, 0.1);
}

TEST(DecodeCenterline, RegionWithoutCenterlineHasNoCue) {
    Synth s = Synth::standard();
    // An island (x in [20, 60)) separated from the rest by a dark band, on
    // the far side of the x centerline at projector x = 400.
    for (int y = 0; y < s.camera.height; ++y)
        for (int x = 60; x < 70; ++x)
            s.gain.at(x, y) = 1.0f;
    const Sequence seq{fpp::WhiteBlock{}, phase(Axis::x, 20, 8), centerline(Axis::x, 400)};
    const CaptureSet set = s.capture(seq);
    const DecodeResult r = fpp::decode(set);
    EXPECT_EQ(r.method_x, "centerline");
    for (int y = 10; y < 290; y += 7)
        for (int x = 20; x < 58; x += 3) {
            EXPECT_TRUE(r.mask.at(x, y) & fpp::kDecodeNoCue) << x << "," << y;
            EXPECT_TRUE(std::isnan(r.proj_x.at(x, y)));
        }
    Image<float> right = s.truth_x;
    for (int y = 0; y < s.camera.height; ++y)
        for (int x = 0; x < 72; ++x)
            right.at(x, y) = std::numeric_limits<float>::quiet_NaN();
    const Accuracy a = accuracy(r.proj_x, right, 20);
    EXPECT_EQ(a.unwrap_errors, 0u);
    EXPECT_GT(a.coverage(), 0.995);
}

} // namespace
