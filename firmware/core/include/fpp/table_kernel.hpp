#pragma once
// The reconstruction kernel: decoded phase + coefficient table -> X, Y, Z per
// camera pixel (camera frame, mm), in fixed-size tiled loops.
//
// For each tile of the table: the tile's phase is gathered into a
// tile-sized buffer, normalised (t = (p - centre) * inv_half_range), the
// cubics evaluated by Horner's rule, and X, Y, Z scattered to the cloud.
// Loops have fixed trip counts per tile and no branches, so the compiler
// vectorises them for the target (NEON on AArch64, SSE/AVX on x86-64).
// Tiles run on the pool's threads; nothing is allocated per pixel or per
// tile (one scratch buffer per worker, allocated once per call at most).
//
// A tile without any finite phase (background) is written as NaN without
// reading its coefficients (also its sigma_z when asked for). A pixel gets
// NaN (no point) when its phase is NaN, it has no model, or |t| > 1 (phase
// outside the range it was calibrated for).

#include "fpp/coefficient_table.hpp"
#include "fpp/image.hpp"
#include "fpp/point_cloud.hpp"

#include <cstddef>

namespace fpp {

class ThreadPool;

struct TableApplyStats {
    std::size_t phase_valid = 0;  // pixels with a finite phase
    std::size_t points = 0;       // pixels given a point
    std::size_t no_model = 0;     // finite phase, pixel without a model
    std::size_t out_of_range = 0; // finite phase, |t| > 1
};

// Applies `table` to `phase` (1 channel, the table's camera size, projector px
// along the table's phase axis, NaN = not decoded) into cloud.xyz (resized to
// 3 channels of the camera size if needed; quality and intensity untouched).
// `pool` null: the process-wide pool.
//
// With `coordinate_sigma` (1 channel, camera size: the predicted standard
// deviation of the phase, projector px, e.g. from fpp/phase_noise.hpp), also
// fills cloud.sigma_z (resized if needed) with the predicted standard
// deviation of Z, mm: |dZ/dp| * coordinate_sigma, dZ/dp from the pixel's own
// cubic (its derivative in t by Horner's rule, times inv_half_range; for the
// rational model the quotient rule), NaN where there is no point. Without
// it, cloud.sigma_z is left empty.
//
// Throws std::invalid_argument if the phase image's (or the sigma image's)
// size differs from the table's camera size.
TableApplyStats apply_table(const CoefficientTable& table, const Image<float>& phase,
                            PointCloud& cloud, ThreadPool* pool = nullptr,
                            const Image<float>* coordinate_sigma = nullptr);

} // namespace fpp
