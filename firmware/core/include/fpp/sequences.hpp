#pragma once
// Named pattern sequences, so that people and tests can ask for a standard
// scan without writing YAML.

#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

#include <string>
#include <vector>

namespace fpp {

// Names (W, H = projector width and height; every Gray block has the fewest
// bits that cover the projector's extent on its axis, see gray_bits_needed):
//   "gray-xy"         white, black, 8-step phase (period 20) + complementary Gray, x then y
//   (default) "gray-x"          the same, x only "plain-gray-x"    white, black, 8-step phase +
//   plain Gray code, x "inverse-gray-x"  8-step phase + complementary Gray code with inverse
//   frames, x
//                     (no white/black: each bit is thresholded against its inverse)
//   "multi-period-x"  8-step phase at periods 20, 160 and W (one period over the
//                     whole projector), x
//   "heterodyne-x"    three-frequency heterodyne, 8-step phase with 64, 63 and 56
//                     fringes across the width (periods W/64, W/63, W/56), x
//   "centerline-xy"   the paper's: white, then 8-step phase (period 20) + a
//                     centerline frame, x then y. The line is 2 projector pixels
//                     wide (a 1-pixel line can fall between camera pixels and
//                     disappear after defocus), centred at (W-1)/2 resp. (H-1)/2,
//                     i.e. columns W/2-1 and W/2 for an even W
//   "slstudio-like-x" as SLStudio's example data: 3-step phase with period W/16,
//                     then a 3-step one-period cue (period W), shift_sign -1, x
// Throws std::invalid_argument for an unknown name or a non-positive projector size.
Sequence standard_sequence(const std::string& name, Size projector);
std::vector<std::string> standard_sequence_names();

// Fewest Gray bits so that floor(p / period) fits for every projector pixel
// p in [0, extent - 1].
int gray_bits_needed(double period, int extent);

} // namespace fpp
