#pragma once
// Where a calibration pose's decoded maps sample the board's bright flat
// parts: the white squares of a checkerboard and its white margin, away
// from every dark/bright edge. There the phase is the projector coordinate
// of a known plane's point; at an edge the camera's blur mixes two albedos
// and biases it, and on dark squares its noise is many times larger.
//
// A pixel is kept when it decoded (x, and y when asked), its fringe
// modulation is at least `min_modulation_fraction` of the pose's bright
// level (the 90th percentile of the decoded pixels' modulation), and every
// pixel within `erosion_px` (a square window) is kept as well.

#include "fpp/decoder.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <cstdint>
#include <vector>

namespace fpp::calib {

struct BrightBoardOptions {
    double min_modulation_fraction = 0.5;
    int erosion_px = 3;
    // Throws std::invalid_argument naming the first bad field.
    void validate() const;
};

// 1 where the pixel samples the board's bright parts, 0 elsewhere. Throws
// std::invalid_argument when `need_y` and the capture decodes no y.
Image<std::uint8_t> bright_board_mask(const DecodeResult& decoded, bool need_y,
                                      const BrightBoardOptions& options = {});

// Fraction of the decoded pixels that the mask keeps (0 when none decoded).
double bright_fraction(const DecodeResult& decoded, const Image<std::uint8_t>& mask);

// Dense samples for the stereo calibration: the masked pixels on a square
// grid of `step` px (camera pixel, decoded projector pixel x and y).
void dense_projector_samples(const DecodeResult& decoded, const Image<std::uint8_t>& mask, int step,
                             std::vector<Vec2>& camera, std::vector<Vec2>& projector);

} // namespace fpp::calib
