#pragma once
// Frames synthesised from the spec's pattern formulas for the decoder's unit
// tests: a known projector-coordinate map per camera pixel, 8-bit projector
// patterns sampled by linear interpolation (what a projector pixel grid and a
// camera see), scaled by a smooth gain, quantised to 8 bit.

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "pattern_blocks.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <ostream>
#include <random>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace fpp::test::synthetic {

using fpp::Axis;
using fpp::CaptureSet;
using fpp::DecodeOptions;
using fpp::DecodeResult;
using fpp::Frame;
using fpp::Image;
using fpp::Sequence;
using fpp::Size;

inline constexpr double kPi = std::numbers::pi;

// Ideal intensity in [0, 1] of frame `k` of a block at projector coordinate q
// along the block's axis (firmware/core/formats/capture-set.md).
inline double intensity(const fpp::PatternBlock& block, int k, double q) {
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

inline Axis block_axis(const fpp::PatternBlock& block) {
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

using fpp::test::gray;
using fpp::test::phase;

inline fpp::CenterlineBlock centerline(Axis axis, double position) {
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
inline Accuracy accuracy(const Image<float>& decoded, const Image<float>& truth, double period,
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
inline DecodeResult stream(const CaptureSet& set, const DecodeOptions& options = {}) {
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

inline std::vector<NamedSequence> method_sequences() {
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

// Names the parameter in test output (found by argument-dependent lookup).
inline void PrintTo(const NamedSequence& s, std::ostream* os) {
    *os << s.name;
}

} // namespace fpp::test::synthetic
