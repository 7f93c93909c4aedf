#pragma once
// Unwrapping steps that look at neighbouring pixels: the repair of plain Gray
// code at period edges, and the centerline method (spatial unwrapping made
// absolute by the pixels that see the centerline).

#include "fpp/image.hpp"

#include <cstdint>

namespace fpp::detail {

// Plain Gray code cannot tell which side of a code edge a pixel near the edge
// belongs to. For each pixel marked `edge` whose estimate is finite, each of
// the four directions (left, right, up, down) looks for the first two non-edge
// finite estimates within `reach` px (the walk stops at a pixel without
// estimate) and extrapolates them linearly to the pixel, unless their slope
// exceeds `max_slope` px per pixel (they straddle a step). The prediction
// votes for the candidate p - period, p or p + period within `tolerance` px,
// if any. The pixel takes the candidate when all votes agree; with no vote or
// conflicting votes it is flagged kDecodeUnwrapInconsistent. So a pixel is
// moved only when its own surface says so, and a pixel between two surfaces
// one period apart (an occlusion edge) is masked rather than guessed. Only
// rows [y0, y1) of `out` and `mask` are written; `estimate` and `edge` are read.
struct GrayRepairParams {
    float period = 0;
    int reach = 10;
    float tolerance = 0;
    float max_slope = 0;
};
void repair_plain_gray_rows(Size size, int y0, int y1, const float* estimate,
                            const std::uint8_t* edge, const GrayRepairParams& params, float* out,
                            std::uint8_t* mask);

// Centerline method. Pixels with enough modulation and no saturation are
// grouped into regions of 4-neighbours whose wrapped phases differ by at most
// `jump_gate` periods (larger steps are surface discontinuities, not fringe
// wraps); inside a region the phase is unwrapped along the smoothest links
// first (bucket queue on the wrapped difference). Each region is made absolute
// by its centerline pixels: pixels brighter than the phase mean in the
// centerline frame whose wrapped position matches the line position within
// half the line width + 1 px vote for a fringe-order offset; the offset needs
// `min_votes` votes and a two-thirds majority. Regions without votes get
// kDecodeNoCue, regions with disputed votes kDecodeUnwrapInconsistent.
struct CenterlineParams {
    float period = 0;
    double position = 0;
    double half_width = 0.5;
    float min_modulation = 0; // DN
    std::uint8_t sat_bit = 1;
    float jump_gate = 0.25f;
    int min_votes = 3;
};
void unwrap_centerline(Size size, const float* fraction, const float* modulation,
                       const std::uint8_t* sat, const std::uint8_t* line,
                       const CenterlineParams& params, std::int32_t* region, std::int32_t* next,
                       float* out, std::uint8_t* mask);

} // namespace fpp::detail
