#pragma once
// Separable Gaussian blur of single-channel float images (internal): optical
// defocus of the projector and the camera.

#include "fpp/parallel.hpp"

#include <vector>

namespace fpp::sim::detail {

enum class Border { zero, clamp };

// Normalised taps w[-r..r] (r = ceil(3.5 sigma)), returned as w[0..2r].
std::vector<float> gaussian_kernel(double sigma);

// Blurs a width x height single-channel image in place, rows split over
// `pool`. Border::zero treats outside as black (projector image: no light
// beyond its edge); Border::clamp repeats the edge (camera image: the scene
// continues). `scratch` is resized as needed and may be reused between calls.
void gaussian_blur(float* image, int width, int height, double sigma, Border border,
                   ThreadPool& pool, std::vector<float>& scratch);

} // namespace fpp::sim::detail
