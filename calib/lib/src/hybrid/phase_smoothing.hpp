#pragma once
// Smoothing of a flat board's decoded phase map before the per-pixel fits
// (internal to the hybrid calibration): the board is flat and evenly lit, so
// its phase varies smoothly over the image, while each pixel's phase noise
// would otherwise go straight into that pixel's model, which has one sample
// per pose to average it. A local quadratic least-squares fit (separable
// Savitzky-Golay, window 2r + 1) keeps any quadratic variation of the phase
// exactly and divides the noise by about 7 at r = 7.

#include "fpp/image.hpp"
#include "fpp/parallel.hpp"

namespace fpp::calib {

// A pixel whose window is not all finite (the image's border, a hole, a dark
// square of a checkerboard) keeps its own phase. r = 0 leaves the phase as it is.
void smooth_phase(Image<float>& phase, int r, ThreadPool& pool);

} // namespace fpp::calib
