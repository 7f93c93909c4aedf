#pragma once
// The per-pixel fits of a hybrid table: from many board poses, each giving
// camera pixels a sample (decoded projector coordinate, 3D point on the
// board), per camera pixel a model from phase to X, Y, Z
// (fpp/coefficient_table.hpp). Shared by both hybrid procedures
// (hybrid_calibrate.hpp): the paper's flat boards placed by SV, and
// checkerboards placed by the camera.
//
// Conventions: camera frame, mm; phase = decoded projector column (projector
// px); planes n . X = d with |n| = 1 and n_z > 0.
//
// The sample of a pixel at a pose is the point of the pose's plane that the
// pixel sees, by `correction`:
//   along_ray           where the pixel's camera ray (xn, yn, 1) meets the
//                       plane: Z = d / (n . (xn, yn, 1)), X = xn Z, Y = yn Z
//   perpendicular_foot  the paper's: the SV point (xn z, yn z, z) moved onto
//                       the plane along its normal (needs sv_depth)
// A stereo model can add samples (ModelSampleSource) over the depth range
// that a pixel's board samples reached, filling the poses between them.
// Per pixel the phase is normalised to t in [-1, 1] over the range of its
// samples; the fits are weighted least squares in double precision
// (models: coefficient_table.hpp; rational by Sanathanan-Koerner, a second
// solve weighted by 1 / (1 + d t)^2). A pixel gets no model (NaN centre)
// with fewer than min_samples samples or ill-conditioned normal equations
// (samples bunched at one phase), and a rational model whose pole is not
// well outside the calibrated range.

#include "fpp/coefficient_table.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace fpp::calib {

struct BoardPlane {
    Vec3 normal{0, 0, 1}; // unit, n_z > 0
    double d = 0;         // n . X = d (mm); the plane's distance from the camera centre
};

// One board pose's samples.
struct PoseSamples {
    Image<float> phase;    // projector column per camera pixel; NaN = no sample
    Image<float> weight;   // per-sample weight (> 0); empty = 1 everywhere
    Image<float> sv_depth; // SV depth per pixel (perpendicular_foot only); NaN = no sample
    BoardPlane plane;
};

enum class PlaneCorrection { along_ray, perpendicular_foot };

// Samples of one pixel from a stereo model, for the checkerboard procedure:
// the pixel (u, v) and the depth range [z_near, z_far] its board samples
// reached; writes up to `capacity` pairs (projector column, depth along the
// pixel's ray) and returns how many.
using ModelSampleSource = std::function<int(int u, int v, double z_near, double z_far,
                                            double* phase, double* depth, int capacity)>;

struct PixelFitOptions {
    TableModel model = TableModel::rational;
    PlaneCorrection correction = PlaneCorrection::along_ray;
    int min_samples = 6; // board samples a pixel needs
    // Weight of each board sample in the fit (the pose's weight image
    // scales it); 0: board samples only set a pixel's coverage and depth
    // range, the model's samples alone are fitted.
    double board_weight = 1;
    // Model samples added to every pixel with enough board samples (along
    // the ray only), each of weight model_weight.
    ModelSampleSource model_samples;
    int model_sample_count = 0;
    double model_weight = 1;
    // Largest ratio of the normal equations' largest to smallest pivot.
    double max_condition = 1e7;
    int tile_width = 32;
    int tile_height = 8;
    int threads = 0; // 0 = all cores
};

struct PixelFit {
    CoefficientTable table;
    // Per camera pixel (NaN without a model): weighted RMS of the fit's
    // residuals in X, Y, Z (mm), and the predicted standard deviation of the
    // model's depth from those residuals (mm; RMS over the calibrated range:
    // residual sigma x sqrt(coefficients / samples)).
    Image<float> rms_x, rms_y, rms_z, sigma_z;
    Image<std::uint16_t> samples; // samples per pixel
    std::size_t modelled = 0, too_few = 0, ill_conditioned = 0;
    double seconds = 0;
};

// `rays`: the camera's undistorted ray (xn, yn) per pixel, 2 channels (NaN
// where unknown); `info`: the table's layout (camera size, tiles, model,
// axis, projector, hash, time). Every PoseSamples image has the camera's
// size. Throws std::invalid_argument for sizes that disagree, a
// perpendicular_foot correction without sv_depth or with model samples, or
// board_weight 0 without model samples.
PixelFit fit_pixel_models(const std::vector<PoseSamples>& poses, const Image<float>& rays,
                          const TableInfo& info, const PixelFitOptions& options);

// Coefficients of a model (x, y, z polynomial; or z alone) per pixel.
int model_coefficients(TableModel model); // 4 (cubic) or 5 (rational)

} // namespace fpp::calib
