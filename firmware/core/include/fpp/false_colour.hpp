#pragma once
// False-colour rendering of scalar maps for people to look at (PNG previews).

#include "fpp/image.hpp"

#include <cstdint>

namespace fpp {

// Maps v in [lo, hi] through a blue-cyan-green-yellow-red ramp to 3-channel
// RGB; NaN (and values when lo >= hi) become black. Values outside are clamped.
Image<std::uint8_t> false_colour(const Image<float>& values, float lo, float hi);

// The ramp itself, t in [0, 1] -> RGB.
void ramp_colour(float t, std::uint8_t rgb[3]);

} // namespace fpp
