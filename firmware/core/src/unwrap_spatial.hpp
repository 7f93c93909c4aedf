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

// Centerline method: spatial unwrapping made absolute by the centerline.
// 1. Valid pixels (enough modulation, no saturation) are grouped into patches
//    joined by smooth 4-neighbour links: wrapped step at most `jump_gate`
//    periods and second difference (change of step along the link's line) at
//    most `patch_gate`, in this axis's phase and, when `other` is given, in
//    the other axis's wrapped fraction too (a depth step moves both).
//    Patches are unwrapped inside (breadth first).
// 2. Adjacent patches merge, with the fringe-order offset most of their
//    boundary links agree on, when at least `min_links` and half of those
//    links are smooth under the looser `merge_gate` and 4/5 of the smooth ones
//    agree. At an occlusion edge most links jump, so a few that look smooth by
//    chance do not connect two surfaces.
// 3. Pixels lit by the centerline (`line` = 1: brighter than the phase mean in
//    the centerline frame) whose wrapped position matches the line position
//    within half the line width + 1 px, in runs, vote for their group's
//    absolute fringe order; it needs `min_votes` votes and a 2/3 majority.
// Groups without votes get kDecodeNoCue, with disputed votes
// kDecodeUnwrapInconsistent. `state` and `next` are scratch (one int per pixel).
struct CenterlineParams {
    float period = 0;
    double position = 0;
    double half_width = 0.5;
    float min_modulation = 0; // DN
    std::uint8_t sat_bit = 1;
    float jump_gate = 0.25f;
    float patch_gate = 0.04f;
    float merge_gate = 0.1f;
    int min_links = 3;
    int min_votes = 3;
    float highest = 1e30f; // projector extent + 0.5: larger results are flagged inconsistent
};
void unwrap_centerline(Size size, const float* fraction, const float* other,
                       const float* modulation, const std::uint8_t* sat, const std::uint8_t* line,
                       const CenterlineParams& params, std::int32_t* state, std::int32_t* next,
                       float* out, std::uint8_t* mask);

} // namespace fpp::detail
