#pragma once
// Edge-preserving smoothing of decoded projector coordinates.
//
// Why: binary-defocus and dithered fringes (a DLP showing 1-bit patterns)
// leave per-pixel phase noise of a few tenths of a projector pixel, i.e.
// depth noise of several tenths of a millimetre on a long-range rig, while
// the surface itself is smooth over a few camera pixels. Averaging the
// coordinate over a small window of neighbours on the same surface removes
// most of that noise; neighbours on another surface (behind a depth step)
// and pixels without a coordinate must not take part, or edges blur and
// masked pixels leak in.
//
// Method, per pixel with a finite coordinate v (camera pixel (x, y)):
//   1. local gradient (gx, gy): the median of the horizontal (vertical)
//      differences between adjacent finite pixels of the (2r+1)^2 window;
//      the median ignores the few differences that straddle a step;
//   2. each finite neighbour n at offset (dx, dy) is predicted as
//      v + gx dx + gy dy; it takes part only if it lies within `tolerance_px`
//      of that prediction (so a ramp is not mistaken for an edge, and a
//      neighbour across a step larger than the tolerance is left out);
//   3. the result is the centre value of the weighted least-squares plane
//      through the accepted neighbours (the centre included): for a full
//      window their mean; beside an edge or the image border, where the
//      accepted set is lopsided, the plane keeps the ramp from pulling the
//      value toward the side with more neighbours. The change is clamped to
//      the tolerance.
// Consequences: a pixel never moves by more than the tolerance; a linear
// ramp is reproduced exactly; NaN (and infinite) pixels stay as they are
// and contribute nothing; a pixel without accepted neighbours keeps its
// value. Steps smaller than the tolerance are smoothed like noise, and
// strong curvature (within the tolerance over the window) biases the mean:
// pick the tolerance above the noise, e.g. 4 to 5 sigma, and below the
// smallest step worth keeping. By default it is 5 times the noise estimated
// from the image itself (estimate_coordinate_noise).
//
// Measured (tests/unit/core/test_coordinate_filter.cpp): a 5 x 5 window takes
// white noise on a ramp to 0.20 of its RMS; on a simulated scan (paper rig,
// 1 DN read noise) the median error on smooth surfaces drops 3.6x and the
// error within 2 px of depth edges does not grow. On the SLMaster relief
// (dithered fringes, 0.19 projector px of noise) it takes the points more
// than 1 mm off a local quadric from 3.2 % to 1.0 %, the rest on carved
// steps (tests/realdata/test_reconstruct_datasets.cpp).
//
// Units: projector pixels for values and tolerance; camera pixels for the
// radius and sigma. Works on either axis (proj_x, proj_y) independently.

#include "fpp/decoder.hpp"
#include "fpp/image.hpp"

#include <limits>

namespace fpp {

class ThreadPool;

struct CoordinateFilterOptions {
    static constexpr int kMaxRadius = 7;
    int radius = 2; // window (2 radius + 1)^2 camera px; 0 = no smoothing
    // Largest accepted deviation from the local plane, projector px. 0 =
    // automatic: tolerance_sigmas x estimate_coordinate_noise(image), at
    // least kMinTolerance. Too large a tolerance lets curvature in (the
    // mean of a strongly curved patch, e.g. near a sphere's silhouette, is
    // biased by up to the tolerance); too small a one leaves noise in.
    double tolerance_px = 0.0;
    double tolerance_sigmas = 5.0;
    double sigma_px = 0.0; // Gaussian weight of the offset (camera px); 0 = uniform
    int threads = 0;       // workers, 0 = all cores (the process-wide pool)

    static constexpr double kMinTolerance = 1e-3; // projector px

    // Throws std::invalid_argument naming the field if a value is out of
    // range (radius 0..kMaxRadius, tolerance_px >= 0, tolerance_sigmas > 0,
    // sigma_px >= 0, all finite; threads >= 0).
    void validate() const;
};

// Robust per-pixel noise of a coordinate image, projector px: the second
// differences v(x-1) - 2 v(x) + v(x+1) along rows and columns (triples of
// finite pixels; a linear ramp gives 0, white noise of sigma gives sigma
// sqrt(6)), scaled as 1.4826 median |d| / sqrt(6). Edges and curvature
// affect only the few triples that straddle them. 0 with fewer than 16
// triples.
double estimate_coordinate_noise(const Image<float>& coordinates);

// The tolerance `options` gives for this image (options.tolerance_px, or the
// automatic one), projector px.
double resolve_tolerance(const Image<float>& coordinates, const CoordinateFilterOptions& options);

// Smooths one coordinate image (1 channel) into `out` (resized if needed;
// must not be `in`) and returns the tolerance used (projector px). Throws
// std::invalid_argument for a multi-channel input, `out` aliasing `in`, or
// invalid options. `pool`: workers to use (null:
// ThreadPool::shared(options.threads)). Allocates only the output (when its
// size differs) and scratch buffers per call, never per pixel.
double smooth_coordinates(const Image<float>& in, Image<float>& out,
                          const CoordinateFilterOptions& options, ThreadPool* pool = nullptr);

// What smooth_coordinates did to a decode result (NaN for an axis it does
// not have or with radius 0).
struct CoordinateFilterReport {
    double tolerance_x = std::numeric_limits<double>::quiet_NaN(); // projector px
    double tolerance_y = std::numeric_limits<double>::quiet_NaN();
};

// Smooths proj_x and proj_y (those present) of a decode result in place;
// `scratch` holds the intermediate image (reused across calls). The mask,
// modulation and mean are left as they are: the filter never creates or
// removes a coordinate. radius 0 leaves the result untouched.
CoordinateFilterReport smooth_coordinates(DecodeResult& decoded,
                                          const CoordinateFilterOptions& options,
                                          Image<float>& scratch, ThreadPool* pool = nullptr);

} // namespace fpp
