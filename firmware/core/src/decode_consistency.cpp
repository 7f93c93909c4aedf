#include "fpp/decode_consistency.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <variant>
#include <vector>

namespace fpp {

namespace {

// The finest phase block of `axis` and whether another block gives it a cue.
AxisConsistency plan_axis(const Sequence& sequence, Axis axis) {
    AxisConsistency a;
    int cues = 0;
    for (std::size_t i = 0; i < sequence.size(); ++i) {
        const PatternBlock& b = sequence[i];
        if (const auto* p = std::get_if<PhaseBlock>(&b); p && p->axis == axis) {
            ++cues;
            if (a.phase_block < 0 || p->period < a.period) {
                a.phase_block = static_cast<int>(i);
                a.period = p->period;
            }
        } else if (const auto* g = std::get_if<GrayBlock>(&b); g && g->axis == axis) {
            ++cues;
        } else if (const auto* c = std::get_if<CenterlineBlock>(&b); c && c->axis == axis) {
            ++cues;
        }
    }
    a.checked = a.phase_block >= 0 && cues >= 2 && a.period > 0;
    return a;
}

// Walks the lines of `coordinate` (rows for x, columns for y) and counts.
class LineWalker {
public:
    LineWalker(const Image<float>& coordinate, const Image<std::uint8_t>& mask, Axis axis)
        : u_(coordinate.data()), mask_(mask.data()), width_(coordinate.width()),
          height_(coordinate.height()), along_x_(axis == Axis::x) {}

    int lines() const { return along_x_ ? height_ : width_; }
    int length() const { return along_x_ ? width_ : height_; }
    // The coordinate at position k of line l; NaN where not decoded.
    float at(int l, int k) const {
        const std::size_t i = along_x_ ? std::size_t(l) * std::size_t(width_) + std::size_t(k)
                                       : std::size_t(k) * std::size_t(width_) + std::size_t(l);
        return (mask_[i] & kDecodeValid) ? u_[i] : std::nanf("");
    }

private:
    const float* u_;
    const std::uint8_t* mask_;
    int width_, height_;
    bool along_x_;
};

double median_of_three(double a, double b, double c) {
    return std::max(std::min(a, b), std::min(std::max(a, b), c));
}

void measure_axis(const Image<float>& coordinate, const Image<std::uint8_t>& mask, Axis axis,
                  AxisConsistency& a) {
    const LineWalker w(coordinate, mask, axis);
    const double p = a.period;
    const double tol = 0.1 * p;
    // The steps d[0..3] between the five pixels k-2 .. k+2 of line l.
    auto steps = [&](int l, int k, double d[4]) {
        for (int j = 0; j < 4; ++j) {
            const float u0 = w.at(l, k - 2 + j), u1 = w.at(l, k - 1 + j);
            if (!std::isfinite(u0) || !std::isfinite(u1))
                return false;
            d[j] = double(u1) - double(u0);
        }
        return true;
    };
    auto smooth_slope = [&](const double d[4], double& slope) {
        double s[4] = {d[0], d[1], d[2], d[3]};
        std::sort(s, s + 4);
        slope = 0.5 * (s[1] + s[2]);
        for (double v : s)
            if (std::abs(v - slope) >= tol)
                return false;
        return true;
    };
    // Pass 1: the period in camera pixels, from the median step.
    std::vector<float> magnitudes;
    for (int l = 0; l < w.lines(); l += 2)
        for (int k = 2; k + 2 < w.length(); k += 3) {
            double d[4], slope = 0;
            if (steps(l, k, d) && smooth_slope(d, slope))
                magnitudes.push_back(static_cast<float>(std::abs(slope)));
        }
    if (magnitudes.empty())
        return;
    std::nth_element(magnitudes.begin(), magnitudes.begin() + std::ptrdiff_t(magnitudes.size() / 2),
                     magnitudes.end());
    const double step = magnitudes[magnitudes.size() / 2];
    if (!(step > 1e-6 * p))
        return;
    a.camera_period = p / step;
    const int reach = static_cast<int>(std::ceil(1.5 * a.camera_period));
    const bool trend = reach >= 3 && 2 * reach < w.length();
    // Pass 2: smooth pixels, those against the trend, quantised jumps.
    for (int l = 0; l < w.lines(); ++l)
        for (int k = 2; k + 2 < w.length(); ++k) {
            double d[4], slope = 0;
            if (!steps(l, k, d))
                continue;
            if (smooth_slope(d, slope)) {
                ++a.smooth;
                if (trend && k >= reach && k + reach < w.length() && std::abs(slope) > 0.01 * p) {
                    const float before = w.at(l, k - reach), after = w.at(l, k + reach);
                    const double change = double(after) - double(before);
                    if (std::isfinite(change) && std::abs(change) > 0.5 * p &&
                        (change > 0) != (slope > 0))
                        ++a.against;
                }
                continue;
            }
            // A jump between k and k + 1 (d[2]) with smooth sides.
            const double side = median_of_three(d[0], d[1], d[3]);
            if (std::abs(side) >= 0.25 * p || std::abs(d[0] - side) >= tol ||
                std::abs(d[1] - side) >= tol || std::abs(d[3] - side) >= tol)
                continue;
            const double e = std::abs(d[2] - side) / p;
            if ((e >= 0.35 && e <= 0.65) || (e >= 0.85 && e <= 1.15))
                ++a.jumps;
        }
}

std::string percent(double f) {
    char text[32];
    std::snprintf(text, sizeof text, "%.0f %%", 100.0 * f);
    return text;
}

} // namespace

DecodeConsistency check_decode_consistency(const DecodeResult& result, const Sequence& sequence) {
    DecodeConsistency c;
    for (int i = 0; i < 2; ++i) {
        const Axis axis = i == 0 ? Axis::x : Axis::y;
        const Image<float>& coordinate = i == 0 ? result.proj_x : result.proj_y;
        AxisConsistency& a = c.axis[i];
        a = plan_axis(sequence, axis);
        if (!a.checked || coordinate.empty() || result.mask.empty())
            continue;
        measure_axis(coordinate, result.mask, axis, a);
        if (a.smooth < kConsistencyMinSmooth)
            continue;
        const std::string block = "sequence[" + std::to_string(a.phase_block) + "]";
        char rate[32];
        std::snprintf(rate, sizeof rate, "%.2f", a.jumps_per_period());
        std::string found;
        if (a.against_fraction() > kConsistencyMaxAgainst)
            found = "along " + std::string(to_string(axis)) + " the coordinate steps against its " +
                    "own trend on " + percent(a.against_fraction()) +
                    " of the smooth pixels (the phase runs backwards inside each period while " +
                    "its cue counts the periods forwards): check shift_sign of " + block;
        else if (a.jumps_per_period() > kConsistencyMaxJumpsPerPeriod)
            found = "along " + std::string(to_string(axis)) +
                    " the coordinate jumps by half or a whole period between smoothly stepping " +
                    "pixels " + rate +
                    " times per period (a correct description leaves about none: the phase " +
                    "and its cue disagree about where the periods begin): check phase_offset " +
                    "of " + block + ", or the offset of the code block";
        if (found.empty())
            continue;
        c.inconsistent = true;
        c.message += (c.message.empty() ? "" : "; ") + found;
    }
    return c;
}

} // namespace fpp
