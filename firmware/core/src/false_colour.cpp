#include "fpp/false_colour.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace fpp {

namespace {
// Control colours of the ramp, evenly spaced in t. Chosen to be monotonic in
// lightness from the blue end to the yellow, so that order reads at a glance.
constexpr std::array<std::array<float, 3>, 6> kRamp{{
    {0.18f, 0.05f, 0.45f}, // deep blue-violet
    {0.10f, 0.35f, 0.85f}, // blue
    {0.05f, 0.70f, 0.80f}, // cyan
    {0.35f, 0.85f, 0.35f}, // green
    {0.98f, 0.85f, 0.15f}, // yellow
    {0.85f, 0.15f, 0.10f}, // red
}};
} // namespace

void ramp_colour(float t, std::uint8_t rgb[3]) {
    t = std::clamp(t, 0.0f, 1.0f);
    const float scaled = t * static_cast<float>(kRamp.size() - 1);
    const int i = std::min(static_cast<int>(scaled), static_cast<int>(kRamp.size()) - 2);
    const float w = scaled - static_cast<float>(i);
    for (int c = 0; c < 3; ++c) {
        const float v = kRamp[i][c] * (1.0f - w) + kRamp[i + 1][c] * w;
        rgb[c] = static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
    }
}

Image<std::uint8_t> false_colour(const Image<float>& values, float lo, float hi) {
    Image<std::uint8_t> out(values.width(), values.height(), 3, 0);
    if (!(hi > lo))
        return out;
    const float scale = 1.0f / (hi - lo);
    for (int y = 0; y < values.height(); ++y) {
        const float* src = values.row(y);
        std::uint8_t* dst = out.row(y);
        for (int x = 0; x < values.width(); ++x) {
            const float v = src[std::size_t(x) * values.channels()];
            if (std::isnan(v))
                continue;
            ramp_colour((v - lo) * scale, dst + 3 * x);
        }
    }
    return out;
}

} // namespace fpp
