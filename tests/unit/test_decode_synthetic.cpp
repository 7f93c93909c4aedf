// Decoder tests on frames synthesised here from the spec's pattern formulas:
// a known projector-coordinate map per camera pixel, 8-bit projector patterns
// sampled by linear interpolation (what a projector pixel grid and a camera
// see), scaled by a smooth gain, quantised to 8 bit.

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <ostream>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using fpp::Axis;
using fpp::CaptureSet;
using fpp::DecodeOptions;
using fpp::DecodeResult;
using fpp::Frame;
using fpp::Image;
using fpp::Sequence;
using fpp::Size;

constexpr double kPi = std::numbers::pi;

// Ideal intensity in [0, 1] of frame `k` of a block at projector coordinate q
// along the block's axis (firmware/core/formats/capture-set.md).
double intensity(const fpp::PatternBlock& block, int k, double q) {
    if (std::holds_alternative<fpp::WhiteBlock>(block))
        return 1.0;
    if (std::holds_alternative<fpp::BlackBlock>(block))
        return 0.0;
    if (const auto* p = std::get_if<fpp::PhaseBlock>(&block))
        return 0.5 + 0.5 * std::cos(2 * kPi * q / p->period + p->phase_offset +
                                    p->shift_sign * 2 * kPi * k / p->steps);
    if (const auto* g = std::get_if<fpp::GrayBlock>(&block)) {
        int plane = k;
        bool inverted = false;
        if (g->inverse) {
            plane = k / 2;
            inverted = k % 2 == 1;
        }
        const int planes = g->bits + (g->complementary ? 1 : 0);
        const auto n =
            static_cast<unsigned>(std::floor((g->complementary ? 2.0 : 1.0) * q / g->period));
        const unsigned code = n ^ (n >> 1);
        const bool on = ((code >> (planes - 1 - plane)) & 1u) != 0;
        return on != inverted ? 1.0 : 0.0;
    }
    const auto& c = std::get<fpp::CenterlineBlock>(block);
    return std::abs(q - c.position) <= c.width / 2 ? 1.0 : 0.0;
}

Axis block_axis(const fpp::PatternBlock& block) {
    if (const auto* p = std::get_if<fpp::PhaseBlock>(&block))
        return p->axis;
    if (const auto* g = std::get_if<fpp::GrayBlock>(&block))
        return g->axis;
    if (const auto* c = std::get_if<fpp::CenterlineBlock>(&block))
        return c->axis;
    return Axis::x;
}

// A camera view of a projector: truth projector coordinates per camera pixel
// (NaN = no projector light), gain in DN for a fully lit pixel, offset in DN.
struct Synth {
    Size camera{400, 300};
    Size projector{800, 600};
    Image<float> truth_x, truth_y, gain;
    double offset = 12.0;

    // Plane-like affine maps plus a smooth bump; gain varies smoothly.
    static Synth standard() {
        Synth s;
        s.truth_x = Image<float>(s.camera);
        s.truth_y = Image<float>(s.camera);
        s.gain = Image<float>(s.camera);
        for (int y = 0; y < s.camera.height; ++y)
            for (int x = 0; x < s.camera.width; ++x) {
                const double dx = x - 230.0, dy = y - 140.0;
                const double bump = 25.0 * std::exp(-(dx * dx + dy * dy) / (2 * 45.0 * 45.0));
                s.truth_x.at(x, y) = static_cast<float>(15.0 + 1.87 * x + 0.11 * y + bump);
                s.truth_y.at(x, y) = static_cast<float>(12.0 + 0.07 * x + 1.89 * y - 0.6 * bump);
                s.gain.at(x, y) =
                    static_cast<float>(170.0 + 40.0 * std::sin(x * 0.013) * std::cos(y * 0.017));
            }
        return s;
    }

    // 8-bit (or 16-bit: values scaled by 257) frame of one pattern frame.
    Frame render(const fpp::PatternBlock& block, int k, int bit_depth, double noise,
                 std::mt19937& rng) const {
        const Axis axis = block_axis(block);
        const int extent = axis == Axis::x ? projector.width : projector.height;
        std::vector<double> profile(static_cast<std::size_t>(extent));
        for (int i = 0; i < extent; ++i)
            profile[static_cast<std::size_t>(i)] =
                std::round(255.0 * intensity(block, k, i)) / 255.0;
        std::normal_distribution<double> gauss(0.0, noise);
        const double full = bit_depth == 8 ? 255.0 : 65535.0;
        const double scale = bit_depth == 8 ? 1.0 : 257.0;
        Frame f;
        f.bit_depth = bit_depth;
        if (bit_depth == 8)
            f.u8 = Image<std::uint8_t>(camera);
        else
            f.u16 = Image<std::uint16_t>(camera);
        for (int y = 0; y < camera.height; ++y)
            for (int x = 0; x < camera.width; ++x) {
                const double q = axis == Axis::x ? truth_x.at(x, y) : truth_y.at(x, y);
                const double other = axis == Axis::x ? truth_y.at(x, y) : truth_x.at(x, y);
                double v = 0;
                const int other_extent = axis == Axis::x ? projector.height : projector.width;
                if (std::isfinite(q) && std::isfinite(other) && q >= 0 && q <= extent - 1 &&
                    other >= 0 && other <= other_extent - 1) {
                    const double qc = q;
                    const int i0 = std::min(static_cast<int>(qc), extent - 2);
                    const double t = qc - i0;
                    v = (1 - t) * profile[static_cast<std::size_t>(i0)] +
                        t * profile[static_cast<std::size_t>(i0 + 1)];
                }
                double dn = offset + double(gain.at(x, y)) * v;
                if (noise > 0)
                    dn += gauss(rng);
                dn = std::clamp(std::round(dn * scale), 0.0, full);
                if (bit_depth == 8)
                    f.u8.at(x, y) = static_cast<std::uint8_t>(dn);
                else
                    f.u16.at(x, y) = static_cast<std::uint16_t>(dn);
            }
        return f;
    }

    CaptureSet capture(const Sequence& sequence, int bit_depth = 8, double noise = 0.0,
                       unsigned seed = 7) const {
        CaptureSet set;
        set.manifest.camera = camera;
        set.manifest.projector = projector;
        set.manifest.sequence = sequence;
        std::mt19937 rng(seed);
        for (const auto& block : sequence)
            for (int k = 0; k < fpp::frame_count(block); ++k)
                set.frames.push_back(render(block, k, bit_depth, noise, rng));
        return set;
    }
};

fpp::PhaseBlock phase(Axis axis, double period, int steps, int sign = 1, double offset = 0) {
    fpp::PhaseBlock b;
    b.axis = axis;
    b.period = period;
    b.steps = steps;
    b.shift_sign = sign;
    b.phase_offset = offset;
    return b;
}

fpp::GrayBlock gray(Axis axis, double period, int bits, bool complementary, bool inverse = false) {
    fpp::GrayBlock g;
    g.axis = axis;
    g.period = period;
    g.bits = bits;
    g.complementary = complementary;
    g.inverse = inverse;
    return g;
}

fpp::CenterlineBlock centerline(Axis axis, double position) {
    fpp::CenterlineBlock c;
    c.axis = axis;
    c.position = position;
    c.width = 1.0;
    return c;
}

struct Accuracy {
    std::size_t truth = 0, valid = 0, unwrap_errors = 0;
    double rms = 0, max_abs = 0;
    double coverage() const { return truth ? double(valid) / double(truth) : 0; }
};

// Against the truth map; `margin` excludes pixels that close to the border.
Accuracy accuracy(const Image<float>& decoded, const Image<float>& truth, double period,
                  int margin = 2) {
    Accuracy a;
    double sum = 0;
    for (int y = margin; y < truth.height() - margin; ++y)
        for (int x = margin; x < truth.width() - margin; ++x) {
            const float t = truth.at(x, y);
            if (!std::isfinite(t))
                continue;
            ++a.truth;
            const float d = decoded.at(x, y);
            if (!std::isfinite(d))
                continue;
            ++a.valid;
            const double e = std::abs(double(d) - double(t));
            if (e > period / 2) {
                ++a.unwrap_errors;
                continue;
            }
            sum += e * e;
            a.max_abs = std::max(a.max_abs, e);
        }
    const std::size_t ok = a.valid - a.unwrap_errors;
    a.rms = ok ? std::sqrt(sum / double(ok)) : 0;
    return a;
}

template <class T> bool same_bytes(const Image<T>& a, const Image<T>& b) {
    if (a.size() != b.size() || a.channels() != b.channels())
        return false;
    if (a.empty())
        return b.empty(); // memcmp must not see null pointers
    return std::memcmp(a.data(), b.data(), a.pixel_count() * a.channels() * sizeof(T)) == 0;
}

// Streams the frames through one buffer that is overwritten after each push,
// as a camera's buffer goes back to its stream: the decoder must keep what it
// reads later (a phase block is decoded in slices over the following frames).
DecodeResult stream(const CaptureSet& set, const DecodeOptions& options = {}) {
    fpp::StreamingDecoder decoder(set.manifest.sequence, set.manifest.camera,
                                  set.manifest.projector, options);
    fpp::Frame buffer;
    for (const auto& f : set.frames) {
        buffer = f;
        decoder.push(buffer);
        std::fill(buffer.u8.data(), buffer.u8.data() + buffer.u8.pixel_count(), std::uint8_t{0xA5});
        std::fill(buffer.u16.data(), buffer.u16.data() + buffer.u16.pixel_count(),
                  std::uint16_t{0xA5A5});
    }
    return decoder.finish();
}

// The sequences exercising every unwrapping method.
struct NamedSequence {
    std::string name;
    Sequence sequence;
    std::string method_x, method_y;
    double period_x, period_y;
};

std::vector<NamedSequence> method_sequences() {
    std::vector<NamedSequence> v;
    v.push_back({"complementary-gray",
                 {fpp::WhiteBlock{}, fpp::BlackBlock{}, phase(Axis::x, 20, 8),
                  gray(Axis::x, 20, 6, true), phase(Axis::y, 20, 8), gray(Axis::y, 20, 5, true)},
                 "complementary-gray",
                 "complementary-gray",
                 20,
                 20});
    v.push_back(
        {"plain-gray",
         {fpp::WhiteBlock{}, fpp::BlackBlock{}, phase(Axis::x, 20, 8), gray(Axis::x, 20, 6, false)},
         "gray",
         "",
         20,
         0});
    // Fractional periods: code edges fall between projector pixels (ceil()).
    v.push_back({"complementary-gray-fractional",
                 {phase(Axis::x, 21.3, 8), gray(Axis::x, 21.3, 6, true)},
                 "complementary-gray",
                 "",
                 21.3,
                 0});
    v.push_back({"plain-gray-fractional",
                 {fpp::WhiteBlock{}, fpp::BlackBlock{}, phase(Axis::y, 17.65, 8),
                  gray(Axis::y, 17.65, 6, false)},
                 "",
                 "gray",
                 0,
                 17.65});
    v.push_back({"inverse-gray",
                 {phase(Axis::x, 20, 8), gray(Axis::x, 20, 6, false, true)},
                 "inverse-gray",
                 "",
                 20,
                 0});
    v.push_back({"inverse-complementary-gray",
                 {phase(Axis::y, 16, 4, -1, 0.7), gray(Axis::y, 16, 6, true, true)},
                 "",
                 "inverse-complementary-gray",
                 0,
                 16});
    // Gray thresholded against the phase mean, gray frames before the phase block.
    v.push_back({"gray-before-phase",
                 {gray(Axis::x, 20, 6, true), phase(Axis::x, 20, 12, 1, -kPi)},
                 "complementary-gray",
                 "",
                 20,
                 0});
    v.push_back({"multi-period",
                 {phase(Axis::x, 20, 8), phase(Axis::x, 160, 8), phase(Axis::x, 800, 8)},
                 "multi-period",
                 "",
                 20,
                 0});
    // SLStudio style: 3 steps, negative shift, one-period cue, both axes.
    v.push_back({"one-period-cue",
                 {phase(Axis::x, 50, 3, -1), phase(Axis::x, 800, 3, -1),
                  phase(Axis::y, 37.5, 3, -1), phase(Axis::y, 600, 3, -1)},
                 "multi-period",
                 "multi-period",
                 50,
                 37.5});
    // Beats 420 (20/21) and 280 (21/22.702...), beat of beats 840 >= 800.
    v.push_back({"heterodyne",
                 {phase(Axis::x, 20, 8), phase(Axis::x, 21, 8),
                  phase(Axis::x, 1.0 / (1.0 / 21 - 1.0 / 280), 8)},
                 "heterodyne",
                 "",
                 20,
                 0});
    v.push_back({"heterodyne-two",
                 {phase(Axis::y, 60, 8), phase(Axis::y, 64, 8)},
                 "",
                 "heterodyne",
                 0,
                 60});
    v.push_back({"centerline",
                 {fpp::WhiteBlock{}, phase(Axis::x, 20, 8), centerline(Axis::x, 400),
                  phase(Axis::y, 20, 8), centerline(Axis::y, 300)},
                 "centerline",
                 "centerline",
                 20,
                 20});
    v.push_back({"direct", {phase(Axis::x, 800, 12)}, "direct", "", 800, 0});
    return v;
}

void PrintTo(const NamedSequence& s, std::ostream* os) {
    *os << s.name;
}

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

TEST(DecodeApi, RecycledResultGivesTheSameBytes) {
    const Synth s = Synth::standard();
    const CaptureSet set = s.capture(method_sequences()[0].sequence, 8, 1.0);
    const DecodeResult fresh = fpp::decode(set);
    DecodeResult reused = fpp::decode(s.capture(method_sequences()[0].sequence, 8, 3.0, 99));
    const float* memory = reused.proj_x.data();
    fpp::decode(set, reused);
    EXPECT_EQ(reused.proj_x.data(), memory); // no new allocation
    EXPECT_TRUE(same_bytes(fresh.proj_x, reused.proj_x));
    EXPECT_TRUE(same_bytes(fresh.proj_y, reused.proj_y));
    EXPECT_TRUE(same_bytes(fresh.mask, reused.mask));
    EXPECT_TRUE(same_bytes(fresh.modulation, reused.modulation));
    fpp::StreamingDecoder d(set.manifest.sequence, set.manifest.camera, set.manifest.projector, {},
                            std::move(reused));
    for (const auto& f : set.frames)
        d.push(f);
    const DecodeResult streamed = d.finish();
    EXPECT_EQ(streamed.proj_x.data(), memory);
    EXPECT_TRUE(same_bytes(fresh.proj_x, streamed.proj_x));
    EXPECT_TRUE(same_bytes(fresh.mean, streamed.mean));
}

// One decoder restarted scan after scan, as the scanner uses it: every
// sequence gives the batch decoder's bytes after a finished scan of another
// bit depth and after a scan abandoned part-way, and reuses the images handed
// back to it.
TEST(DecodeApi, RestartedDecoderGivesTheSameBytesScanAfterScan) {
    const Synth s = Synth::standard();
    for (const NamedSequence& ns : method_sequences()) {
        const CaptureSet deep = s.capture(ns.sequence, 16, 40.0, 5);
        const CaptureSet shallow = s.capture(ns.sequence, 8, 1.0, 6);
        fpp::StreamingDecoder d(ns.sequence, s.camera, s.projector);
        auto run = [&](const CaptureSet& set) {
            for (const auto& f : set.frames)
                d.push(f);
            return d.finish();
        };
        const DecodeResult first = run(deep);
        EXPECT_TRUE(same_bytes(first.modulation, fpp::decode(deep).modulation)) << ns.name;
        d.restart(DecodeResult(first));
        // Abandoned after a few frames: the next scan starts from its first frame.
        for (std::size_t i = 0; i < 3 && i < shallow.frames.size(); ++i)
            d.push(shallow.frames[i]);
        d.restart();
        DecodeResult second = run(shallow);
        const DecodeResult batch = fpp::decode(shallow);
        EXPECT_TRUE(same_bytes(batch.proj_x, second.proj_x)) << ns.name;
        EXPECT_TRUE(same_bytes(batch.proj_y, second.proj_y)) << ns.name;
        EXPECT_TRUE(same_bytes(batch.modulation, second.modulation)) << ns.name;
        EXPECT_TRUE(same_bytes(batch.mean, second.mean)) << ns.name;
        EXPECT_TRUE(same_bytes(batch.mask, second.mask)) << ns.name;
        const float* reused = second.modulation.data();
        d.restart(std::move(second));
        const DecodeResult third = run(deep);
        EXPECT_EQ(third.modulation.data(), reused) << ns.name; // no new allocation
        EXPECT_TRUE(same_bytes(first.proj_x, third.proj_x)) << ns.name;
        EXPECT_TRUE(same_bytes(first.mask, third.mask)) << ns.name;
    }
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

// --- API contract -----------------------------------------------------------

Sequence small_sequence() {
    return {fpp::WhiteBlock{}, fpp::BlackBlock{}, phase(Axis::x, 20, 4),
            gray(Axis::x, 20, 6, true)};
}

TEST(DecodeApi, PushRejectsBadFrames) {
    const Synth s = Synth::standard();
    const CaptureSet set = s.capture(small_sequence());
    {
        fpp::StreamingDecoder d(set.manifest.sequence, s.camera, s.projector);
        Frame wrong_size;
        wrong_size.u8 = Image<std::uint8_t>(s.camera.width - 1, s.camera.height);
        EXPECT_THROW(d.push(wrong_size), fpp::InputError);
        Frame twelve = set.frames[0];
        twelve.bit_depth = 12;
        EXPECT_THROW(d.push(twelve), fpp::InputError);
        Frame empty;
        EXPECT_THROW(d.push(empty), fpp::InputError);
        Frame two_channels;
        two_channels.u8 = Image<std::uint8_t>(s.camera, 2);
        EXPECT_THROW(d.push(two_channels), fpp::InputError);
        EXPECT_EQ(d.frames_received(), 0);
        d.push(set.frames[0]);
        Frame deep;
        deep.bit_depth = 16;
        deep.u16 = Image<std::uint16_t>(s.camera);
        try {
            d.push(deep);
            ADD_FAILURE() << "accepted a 16-bit frame after an 8-bit one";
        } catch (const fpp::InputError& e) { // no file: the decoder, and the frame's field
            EXPECT_EQ(e.file(), std::filesystem::path(fpp::kDecoderOrigin));
            EXPECT_EQ(e.field(), "frames[1]");
            EXPECT_NE(std::string(e.what()).find("differs from the first frame's 8"),
                      std::string::npos)
                << e.what();
        }
        EXPECT_EQ(d.frames_received(), 1);
        EXPECT_EQ(d.frames_expected(), static_cast<int>(set.frames.size()));
        EXPECT_THROW(d.finish(), std::logic_error);
    }
    {
        fpp::StreamingDecoder d(set.manifest.sequence, s.camera, s.projector);
        for (const auto& f : set.frames)
            d.push(f);
        EXPECT_THROW(d.push(set.frames[0]), fpp::InputError);
        const DecodeResult r = d.finish();
        EXPECT_FALSE(r.proj_x.empty());
        EXPECT_THROW(d.finish(), std::logic_error);
        EXPECT_THROW(d.push(set.frames[0]), std::logic_error);
    }
    {
        CaptureSet missing = set;
        missing.frames.pop_back();
        EXPECT_THROW(fpp::decode(missing), fpp::InputError);
        CaptureSet mixed = set;
        mixed.frames[3] = Frame{16, {}, Image<std::uint16_t>(s.camera)};
        mixed.folder = "scans/plane";
        try {
            (void)fpp::decode(mixed);
            ADD_FAILURE() << "accepted frames of mixed bit depths";
        } catch (const fpp::InputError& e) { // the capture's manifest, and the frame
            EXPECT_EQ(e.file(), std::filesystem::path("scans/plane/capture.yaml"));
            EXPECT_EQ(e.field(), "frames[3]");
        }
    }
}

TEST(DecodeApi, SixteenBitFramesDecodeLikeEightBit) {
    const Synth s = Synth::standard();
    const CaptureSet set = s.capture(method_sequences()[0].sequence, 16);
    const DecodeResult r = fpp::decode(set);
    const Accuracy a = accuracy(r.proj_x, s.truth_x, 20);
    EXPECT_EQ(a.unwrap_errors, 0u);
    EXPECT_LT(a.rms, 0.03);
    EXPECT_GT(a.coverage(), 0.995);
    EXPECT_TRUE(same_bytes(r.proj_x, stream(set).proj_x));
}

TEST(DecodeApi, OptionsValidation) {
    EXPECT_NO_THROW(DecodeOptions{}.validate());
    auto bad = [](auto mutate) {
        DecodeOptions o;
        mutate(o);
        EXPECT_THROW(o.validate(), fpp::InputError);
    };
    bad([](DecodeOptions& o) { o.min_modulation = -0.01; });
    bad([](DecodeOptions& o) { o.min_modulation = 1.0; });
    bad([](DecodeOptions& o) { o.min_modulation = std::nan(""); });
    bad([](DecodeOptions& o) { o.saturation = 0.0; });
    bad([](DecodeOptions& o) { o.saturation = 1.01; });
    bad([](DecodeOptions& o) { o.max_unwrap_disagreement = 0.0; });
    bad([](DecodeOptions& o) { o.max_unwrap_disagreement = 0.51; });
    bad([](DecodeOptions& o) {
        o.max_unwrap_disagreement = std::numeric_limits<double>::infinity();
    });
    bad([](DecodeOptions& o) { o.threads = -1; });
    try {
        DecodeOptions o;
        o.saturation = 2.0;
        o.validate();
        FAIL() << "no exception";
    } catch (const fpp::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("saturation"), std::string::npos);
        EXPECT_EQ(e.file(), std::filesystem::path(fpp::kDecodeOptionsOrigin));
        EXPECT_EQ(e.field(), "saturation");
    }
    {
        DecodeOptions o; // phase_error's own check, as the decoder's InputError
        o.phase_error.harmonics = 0;
        EXPECT_THROW(o.validate(), fpp::InputError);
    }
    DecodeOptions o;
    o.threads = -3;
    const Synth s = Synth::standard();
    EXPECT_THROW(fpp::StreamingDecoder(small_sequence(), s.camera, s.projector, o),
                 fpp::InputError);
    EXPECT_THROW(fpp::decode(s.capture(small_sequence()), o), fpp::InputError);
}

TEST(DecodeApi, UndecodableSequencesThrow) {
    const Size cam{40, 30}, proj{800, 600};
    auto rejects = [&](const Sequence& seq, const std::string& fragment) {
        try {
            fpp::StreamingDecoder d(seq, cam, proj);
            ADD_FAILURE() << "accepted a sequence that should fail with: " << fragment;
        } catch (const fpp::InputError& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
            EXPECT_EQ(e.file(), std::filesystem::path(fpp::kDecoderOrigin));
        }
    };
    rejects({fpp::WhiteBlock{}, fpp::BlackBlock{}}, "no phase block");
    rejects({}, "no phase block");
    rejects({phase(Axis::x, 20, 8)}, "shorter than the projector extent");
    rejects({phase(Axis::x, 20, 8), gray(Axis::x, 25, 6, true)}, "no phase block on that axis");
    rejects({phase(Axis::x, 20, 8), gray(Axis::x, 20, 4, true)}, "fewer than the projector extent");
    rejects({phase(Axis::x, 20, 8), phase(Axis::x, 22, 8)}, "heterodyne");
    rejects({phase(Axis::x, 20, 8), phase(Axis::x, 20, 4)}, "same period");
    // A gray block alone codes its axis (fpp-capture/2) but needs a threshold.
    rejects({gray(Axis::y, 20, 5, true), phase(Axis::x, 800, 8)},
            "code-only axis needs inverse frames or white and black frames");
    rejects({phase(Axis::x, 20, 2), gray(Axis::x, 20, 6, true)}, "steps");
    // One axis decodable, the other not: still rejected (the user asked for y).
    rejects({phase(Axis::x, 800, 8), phase(Axis::y, 20, 8)}, "axis y");
}

} // namespace
