#pragma once
// Projector pattern generation, exactly the spec's formulas, 8-bit.

#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace fpp {

// Ideal intensity in [0, 1] of frame `frame` of `block` at projector pixel
// (x, y) (pixel centres on integers). White = 1, black = 0.
double pattern_intensity(const PatternBlock& block, int frame, double x, double y);

// Maps a wanted relative intensity (index = round(255 v)) to the 8-bit drive
// level that makes a projector with response (level/255)^gamma emit it.
struct GammaLut {
    std::array<std::uint8_t, 256> level{};
    static GammaLut identity();
    static GammaLut precompensate(double projector_gamma);
};

// Renders one frame at projector resolution: value = round(255 * I) mapped
// through `lut` when given.
Image<std::uint8_t> render_pattern(const PatternBlock& block, int frame, Size projector,
                                   const GammaLut* lut = nullptr);

// Renders every frame of a sequence in capture order.
std::vector<Image<std::uint8_t>> render_sequence(const Sequence& sequence, Size projector,
                                                 const GammaLut* lut = nullptr);

} // namespace fpp
