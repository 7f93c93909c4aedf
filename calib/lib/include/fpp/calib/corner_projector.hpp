#pragma once
// Projector coordinates of checkerboard corners, from the decoded absolute
// phase (projector x and y per camera pixel, fpp::decode).
//
// Methods:
//   poly        the paper's: only pixels of the two white squares at each
//               corner, kept away from every black/white edge (the phase is
//               biased there: blur mixes the two albedos, and black squares
//               have little modulation), a 2D polynomial of the projector
//               coordinate over camera pixels (5th order by default) fitted by
//               least squares, evaluated at the sub-pixel corner;
//   bilinear    the decoded maps sampled at the corner (bilinear);
//   homography  Moreno and Taubin's local homography: camera pixel ->
//               projector coordinate fitted to every decoded pixel in a
//               window around the corner, applied to the corner.
// Default: poly, the most accurate on simulated ground truth (the figures are
// in tests/calib/test_corner_projector.cpp).
//
// Coordinates: projector pixels, pixel centres on integers.

#include "fpp/decoder.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <string>
#include <vector>

namespace fpp::calib {

enum class CornerMethod { poly, bilinear, homography };

const char* to_string(CornerMethod method);
// "poly", "bilinear", "homography"; throws std::invalid_argument otherwise.
CornerMethod corner_method_from_string(const std::string& name);

struct ProjectorCornerOptions {
    CornerMethod method = CornerMethod::poly;
    int poly_order = 5;
    // Pixels nearer than this to a black/white edge are not used (poly); 0 =
    // max(3 px, 12 % of the square size in pixels).
    double erosion_px = 0;
    // Half-size of the homography window in squares (0.5: the window spans
    // half of each of the four squares at the corner).
    double homography_half_window = 0.5;
    // Fewest pixels a fit needs (poly: per coefficient).
    int min_pixels_per_coefficient = 8;
};

struct ProjectorCorners {
    std::vector<Vec2> points; // per camera corner, projector px; NaN where it failed
    std::vector<bool> valid;
    int failed = 0;
};

// `camera_corners`: columns x rows corners in the ordering of corners.hpp;
// `origin_square_black`: as found by find_checkerboard (chooses the white
// squares at each corner). Needs decoded proj_x and proj_y.
ProjectorCorners projector_corners(const DecodeResult& decoded,
                                   const std::vector<Vec2>& camera_corners, int columns, int rows,
                                   bool origin_square_black,
                                   const ProjectorCornerOptions& options = {});

// Bilinear sample of a 1- or multi-channel float image at (x, y); NaN if any
// of the four samples is NaN or outside.
double sample_bilinear(const Image<float>& image, double x, double y, int channel = 0);

} // namespace fpp::calib
