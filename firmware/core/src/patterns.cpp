#include "fpp/patterns.hpp"

#include "fpp/projector_response.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <string>

namespace fpp {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Parameters the formulas cannot evaluate (the capture-set reader rejects
// these too; here they would be a caller's bug, so no file names).
void check_block(const PatternBlock& block) {
    if (const auto* p = std::get_if<PhaseBlock>(&block)) {
        if (!(std::isfinite(p->period) && p->period > 0.0) || p->steps < 1 ||
            !std::isfinite(p->phase_offset) || (p->shift_sign != 1 && p->shift_sign != -1)) {
            throw std::invalid_argument("phase block: invalid period, steps, shift_sign or "
                                        "phase_offset");
        }
        if (p->shifting == PhaseShifting::modulated &&
            (!(std::isfinite(p->carrier_period) && p->carrier_period > 0.0) ||
             p->carrier_steps < 1)) {
            throw std::invalid_argument("phase block: invalid carrier_period or carrier_steps");
        }
    } else if (const auto* m = std::get_if<MicroPhaseBlock>(&block)) {
        const bool periods_ok = std::all_of(m->periods.begin(), m->periods.end(),
                                            [](double v) { return std::isfinite(v) && v > 0.0; });
        const bool extra_ok =
            (m->extra_phase_offsets.empty() ||
             m->extra_phase_offsets.size() + 1 == m->periods.size()) &&
            std::all_of(m->extra_phase_offsets.begin(), m->extra_phase_offsets.end(),
                        [](double v) { return std::isfinite(v); });
        if (m->periods.size() < 2 || !periods_ok || !std::isfinite(m->phase_offset) ||
            (m->shift_sign != 1 && m->shift_sign != -1) || !extra_ok) {
            throw std::invalid_argument("micro_phase block: invalid periods, shift_sign, "
                                        "phase_offset or extra_phase_offsets");
        }
    } else if (const auto* g = std::get_if<GrayBlock>(&block)) {
        if (!(std::isfinite(g->period) && g->period > 0.0) || g->bits < 1 || g->levels < 2 ||
            !std::isfinite(g->offset) ||
            std::pow(static_cast<double>(g->levels), static_cast<double>(g->bits)) > 0x1p30) {
            throw std::invalid_argument("gray block: invalid period, bits, levels or offset");
        }
    } else if (const auto* c = std::get_if<CenterlineBlock>(&block)) {
        if (!std::isfinite(c->position) || !(std::isfinite(c->width) && c->width > 0.0)) {
            throw std::invalid_argument("centerline block: invalid position or width");
        }
    }
}

void check_frame(const PatternBlock& block, int frame) {
    check_block(block);
    const int count = frame_count(block);
    if (frame < 0 || frame >= count) {
        throw std::out_of_range("frame " + std::to_string(frame) + " of a " + pattern_name(block) +
                                " block with " + std::to_string(count) + " frames");
    }
}

double along(Axis axis, double x, double y) {
    return axis == Axis::x ? x : y;
}

// Which code plane a Gray block's frame shows, and whether it is inverted.
struct GrayPlane {
    int plane = 0;      // 0 = MSB
    int planes = 0;     // bits, or bits + 1 when complementary
    double scale = 1.0; // the code is g(floor(scale * p / period))
    bool inverted = false;
};

GrayPlane gray_plane(const GrayBlock& b, int frame) {
    GrayPlane g;
    g.planes = b.bits + (b.complementary ? 1 : 0);
    g.scale = b.complementary ? 2.0 : 1.0;
    if (b.inverse) {
        g.plane = frame / 2;
        g.inverted = (frame % 2) == 1;
    } else {
        g.plane = frame;
    }
    return g;
}

// Digit `digit` (0 = least significant) of code step n's codeword: natural
// base-L digits, or the reflected L-ary Gray code (a digit is mirrored,
// L - 1 - b, when the Gray digits above it sum to an odd number; for L = 2
// this is n ^ (n >> 1)). n is taken modulo L^digits.
int code_digit(const GrayBlock& b, int digits, std::int64_t n, int digit) {
    const std::int64_t levels = b.levels;
    std::int64_t count = 1;
    for (int i = 0; i < digits; ++i)
        count *= levels;
    n = ((n % count) + count) % count;
    std::int64_t place = count / levels;
    int gray_sum = 0;
    for (int i = digits - 1; i >= 0; --i, place /= levels) {
        const auto natural = static_cast<int>((n / place) % levels);
        const int value =
            (b.code == CodeKind::gray && (gray_sum % 2) == 1) ? b.levels - 1 - natural : natural;
        if (i == digit)
            return value;
        gray_sum += value;
    }
    return 0;
}

double gray_intensity(const GrayBlock& b, const GrayPlane& g, double p) {
    const auto n = static_cast<std::int64_t>(std::floor(g.scale * (p - b.offset) / b.period));
    const int digit = b.order == DigitOrder::msb_first ? g.planes - 1 - g.plane : g.plane;
    const double level =
        static_cast<double>(code_digit(b, g.planes, n, digit)) / static_cast<double>(b.levels - 1);
    return g.inverted ? 1.0 - level : level;
}

double fringe(double p, double period, double phase) {
    return 0.5 + 0.5 * std::cos(kTwoPi * p / period + phase);
}

struct IntensityAt {
    int frame;
    double x;
    double y;
    double operator()(const WhiteBlock&) const { return 1.0; }
    double operator()(const BlackBlock&) const { return 0.0; }
    double operator()(const PhaseBlock& b) const {
        const double p = along(b.axis, x, y);
        const double sign = static_cast<double>(b.shift_sign);
        switch (b.shifting) {
        case PhaseShifting::two_plus_one: {
            const double phi = kTwoPi * p / b.period + b.phase_offset;
            if (frame == 0)
                return 0.5 + 0.5 * sign * std::sin(phi);
            return frame == 1 ? 0.5 + 0.5 * std::cos(phi) : 0.5;
        }
        case PhaseShifting::modulated: {
            const int shift = frame / b.carrier_steps;
            const int carrier_shift = frame % b.carrier_steps;
            const double q = b.axis == Axis::x ? y : x;
            return fringe(p, b.period,
                          b.phase_offset + sign * kTwoPi * shift / static_cast<double>(b.steps)) *
                   fringe(q, b.carrier_period,
                          kTwoPi * carrier_shift / static_cast<double>(b.carrier_steps));
        }
        case PhaseShifting::standard:
            break;
        }
        return fringe(p, b.period,
                      b.phase_offset + sign * kTwoPi * static_cast<double>(frame) /
                                           static_cast<double>(b.steps));
    }
    double operator()(const MicroPhaseBlock& b) const {
        const double p = along(b.axis, x, y);
        if (frame < 3) {
            const double shift = static_cast<double>(b.shift_sign) * kTwoPi * frame / 3.0;
            return fringe(p, b.periods[0], b.phase_offset + shift);
        }
        const auto f = static_cast<std::size_t>(frame - 2); // period index, 1 .. F - 1
        const double extra = b.extra_phase_offsets.empty() ? 0.0 : b.extra_phase_offsets[f - 1];
        return fringe(p, b.periods[f], b.phase_offset + extra);
    }
    double operator()(const GrayBlock& b) const {
        return gray_intensity(b, gray_plane(b, frame), along(b.axis, x, y));
    }
    double operator()(const CenterlineBlock& b) const {
        return std::abs(along(b.axis, x, y) - b.position) <= 0.5 * b.width ? 1.0 : 0.0;
    }
};

Axis block_axis(const PatternBlock& block) {
    if (const auto* p = std::get_if<PhaseBlock>(&block))
        return p->axis;
    if (const auto* g = std::get_if<GrayBlock>(&block))
        return g->axis;
    if (const auto* c = std::get_if<CenterlineBlock>(&block))
        return c->axis;
    if (const auto* m = std::get_if<MicroPhaseBlock>(&block))
        return m->axis;
    return Axis::x; // white and black are uniform
}

std::uint8_t to_level(double intensity, const GammaLut* lut) {
    const double clamped = std::clamp(intensity, 0.0, 1.0);
    const auto index = static_cast<std::size_t>(std::lround(255.0 * clamped));
    return lut ? lut->level[index] : static_cast<std::uint8_t>(index);
}

} // namespace

double pattern_intensity(const PatternBlock& block, int frame, double x, double y) {
    check_frame(block, frame);
    return std::visit(IntensityAt{frame, x, y}, block);
}

GammaLut GammaLut::identity() {
    GammaLut lut;
    for (std::size_t i = 0; i < lut.level.size(); ++i)
        lut.level[i] = static_cast<std::uint8_t>(i);
    return lut;
}

GammaLut GammaLut::precompensate(double projector_gamma) {
    if (!std::isfinite(projector_gamma) || projector_gamma <= 0.0) {
        throw std::invalid_argument("GammaLut::precompensate: projector_gamma must be a positive "
                                    "finite number, got " +
                                    std::to_string(projector_gamma));
    }
    // Emitted relative intensity of drive level c, in units of 1/255.
    auto emitted = [projector_gamma](int c) {
        return 255.0 * std::pow(static_cast<double>(c) / 255.0, projector_gamma);
    };
    GammaLut lut;
    for (int v = 0; v < 256; ++v) {
        // The exact inverse lies between two levels; the response is monotonic,
        // so the nearest emitted value is at one of them.
        const double exact =
            255.0 * std::pow(static_cast<double>(v) / 255.0, 1.0 / projector_gamma);
        const int below = std::clamp(static_cast<int>(std::floor(exact)), 0, 255);
        const int above = std::min(below + 1, 255);
        const double target = static_cast<double>(v);
        const int best =
            std::abs(emitted(above) - target) < std::abs(emitted(below) - target) ? above : below;
        lut.level[std::size_t(v)] = static_cast<std::uint8_t>(best);
    }
    return lut;
}

GammaLut GammaLut::from_response(const ProjectorResponse& response, double emitted_gamma) {
    if (!(emitted_gamma >= 1.0 && emitted_gamma <= 4.0)) {
        throw std::invalid_argument("GammaLut::from_response: emitted_gamma must be in [1, 4], "
                                    "got " +
                                    std::to_string(emitted_gamma));
    }
    response.validate();
    std::array<double, 256> emitted{}; // non-decreasing in the level
    for (std::size_t c = 0; c < emitted.size(); ++c)
        emitted[c] = response.at(double(c));
    GammaLut lut;
    for (std::size_t v = 0; v < lut.level.size(); ++v) {
        const double target = std::pow(static_cast<double>(v) / 255.0, emitted_gamma);
        // The nearest emitted light is at the first level reaching the
        // target or at the one before it.
        const auto above = std::lower_bound(emitted.begin(), emitted.end(), target);
        std::size_t best =
            above == emitted.end() ? emitted.size() - 1 : std::size_t(above - emitted.begin());
        if (best > 0 && std::abs(emitted[best - 1] - target) <= std::abs(emitted[best] - target)) {
            best -= 1;
        }
        lut.level[v] = static_cast<std::uint8_t>(best);
    }
    return lut;
}

double compensation_emitted_gamma(const Sequence& sequence) {
    for (const PatternBlock& block : sequence) {
        if (const auto* p = std::get_if<PhaseBlock>(&block); p && p->steps < 4)
            return 1.0;
    }
    return 2.0;
}

Image<std::uint8_t> render_pattern(const PatternBlock& block, int frame, Size projector,
                                   const GammaLut* lut) {
    check_frame(block, frame);
    if (projector.width <= 0 || projector.height <= 0) {
        throw std::invalid_argument("render_pattern: projector size must be positive");
    }
    Image<std::uint8_t> image(projector);
    const Axis axis = block_axis(block);
    const int extent = axis == Axis::x ? projector.width : projector.height;

    const auto* phase = std::get_if<PhaseBlock>(&block);
    if (phase && phase->shifting == PhaseShifting::modulated) {
        // The one pattern that varies along both axes.
        for (int y = 0; y < projector.height; ++y) {
            std::uint8_t* row = image.row(y);
            for (int x = 0; x < projector.width; ++x) {
                row[x] = to_level(pattern_intensity(block, frame, x, y), lut);
            }
        }
        return image;
    }
    // Every other pattern varies along one axis only: compute that profile
    // once and replicate it.
    std::vector<std::uint8_t> profile(static_cast<std::size_t>(extent));
    const IntensityAt at_x{frame, 0.0, 0.0};
    for (int i = 0; i < extent; ++i) {
        IntensityAt at = at_x;
        (axis == Axis::x ? at.x : at.y) = static_cast<double>(i);
        profile[std::size_t(i)] = to_level(std::visit(at, block), lut);
    }
    const std::size_t width = std::size_t(projector.width);
    for (int y = 0; y < projector.height; ++y) {
        std::uint8_t* row = image.row(y);
        if (axis == Axis::x) {
            std::memcpy(row, profile.data(), width);
        } else {
            std::memset(row, profile[std::size_t(y)], width);
        }
    }
    return image;
}

std::vector<Image<std::uint8_t>> render_sequence(const Sequence& sequence, Size projector,
                                                 const GammaLut* lut) {
    std::vector<Image<std::uint8_t>> frames;
    frames.reserve(std::size_t(frame_count(sequence)));
    for (const auto& block : sequence) {
        const int count = frame_count(block);
        for (int k = 0; k < count; ++k)
            frames.push_back(render_pattern(block, k, projector, lut));
    }
    return frames;
}

} // namespace fpp
