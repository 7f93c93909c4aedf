#pragma once
// Stereo-vision (SV) reconstruction: camera pixel + decoded projector
// coordinate(s) -> 3D point in the camera frame, with both lenses' distortion
// compensated (the paper's SV model, its eq. 1-3; the baseline that its
// hybrid model is compared with).
//
// Per camera pixel (u, v) the undistorted camera ray is d = (xn, yn, 1)
// (StereoCalibration::camera_ray: the camera's correction grid removed, then
// LensModel::pixel_to_normalised, skew included); the point is s d, s = Z.
// The projector's pixel of a point is its lens model's projection plus its
// correction grid, when the calibration has one.
//
// x only (vertical fringes): the point must project to projector column x_p.
//   The projector's distortion makes the set of points with column x_p a
//   curved surface, not a plane. Along the ray the projector's undistorted
//   normalised coordinates follow the epipolar line yn = a + b xn; the
//   solver finds xn on it such that the distorted projection has column x_p,
//   i.e. the fixed point of the paper's iteration (project the guess, take its
//   distorted row, undistort (x_p, row) to get the plane, intersect, repeat).
//   Default solver: Newton on xn along the epipolar line, started from the
//   distortion-free plane (1 or 2 steps to 1e-6 px on the paper's rig). The
//   paper's plane iteration is available for comparison
//   (XOnlySolver::plane_iteration: 2 or 3 iterations, each undistorting a
//   projector pixel, about 4x slower).
// x and y: the projector pixel is undistorted directly; the point is the
//   midpoint of the common perpendicular of the camera and projector rays
//   (least-squares closest point); the rays' gap is reported.
//
// Rejected (no point): pixels the decoder did not decode, points behind the
// camera or the projector, degenerate geometry (ray parallel to the plane of
// constant column, parallel rays), a solve that does not converge, a
// projector coordinate (solved row in x-only mode) further than
// `projector_margin_px` outside the projector image, and in xy mode rays
// further apart than max_ray_gap_mm.
//
// A reconstructor precomputes the camera rays once (per calibration) and
// reuses them, and its thread pool, for every scan. reconstruct() allocates
// only when the output cloud does not yet have the camera's size.

#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/decoder.hpp"
#include "fpp/image.hpp"
#include "fpp/point_cloud.hpp"

#include <cstddef>
#include <limits>
#include <memory>
#include <string>

namespace fpp {
class ThreadPool;
}

namespace fpp::calib {

enum class ReconstructAxes {
    automatic, // xy when the capture decodes both axes, else x
    x,         // projector column only
    xy,        // projector column and row
};
// "auto", "x", "xy"; throws std::invalid_argument otherwise.
ReconstructAxes parse_axes(const std::string& name);
const char* to_string(ReconstructAxes axes);

enum class XOnlySolver {
    newton,          // Newton along the epipolar line (default)
    plane_iteration, // the paper's fixed-point iteration (undistort, intersect, repeat)
};

struct SvOptions {
    double tolerance_px = 1e-6; // x only: |column of the solution - x_p|, projector px
    int max_iterations = 20;    // x only: per pixel
    XOnlySolver solver = XOnlySolver::newton;
    // Projector coordinates (x-only: the solved row) further outside the
    // projector image [-0.5, W-0.5] x [-0.5, H-0.5] than this are rejected:
    // no projector light reaches such points. Negative: no check.
    double projector_margin_px = 1.0;
    // xy: rays further apart than this (mm) give no point.
    double max_ray_gap_mm = std::numeric_limits<double>::infinity();
    int threads = 0; // 0 = all cores
};

struct SvStats {
    ReconstructAxes axes = ReconstructAxes::x; // the mode used
    std::size_t decoded = 0;                   // pixels with the needed coordinates decoded
    std::size_t points = 0;                    // pixels given a point
    std::size_t not_converged = 0;             // x only
    std::size_t outside_projector = 0; // solved or decoded projector coordinate outside its image
    std::size_t rejected = 0;   // other geometry checks (behind a device, degenerate, ray gap)
    std::size_t iterations = 0; // x only: solver steps over all points
    int max_iterations = 0;     // x only: most steps at one pixel
    double rms_ray_gap_mm = 0;  // xy: over the points
    double max_ray_gap_mm = 0;  // xy
    double mean_iterations() const { return points ? double(iterations) / double(points) : 0.0; }
};

class SvReconstructor {
public:
    // Throws std::invalid_argument if the calibration's sizes are unknown or
    // its lenses are not usable (non-positive focal lengths).
    explicit SvReconstructor(const StereoCalibration& calibration, const SvOptions& options = {});
    ~SvReconstructor();
    SvReconstructor(SvReconstructor&&) noexcept;
    SvReconstructor& operator=(SvReconstructor&&) noexcept;

    const StereoCalibration& calibration() const { return calibration_; }
    const SvOptions& options() const { return options_; }
    // Undistorted normalised camera ray (xn, yn) per camera pixel, 2 channels;
    // NaN where the camera model cannot be inverted.
    const Image<float>& camera_rays() const { return rays_; }

    // Reconstructs one decoded scan into `cloud` (xyz, quality = modulation,
    // intensity = mean; NaN where no point). `axes` automatic picks xy when
    // both are decoded. Throws std::invalid_argument if the decode result is
    // not of the camera's size or lacks an axis the mode needs.
    SvStats reconstruct(const DecodeResult& decoded, ReconstructAxes axes, PointCloud& cloud) const;

    // One pixel (for tests and tools): camera pixel (u, v), projector column
    // (and row). Return false when the pixel gets no point (see above);
    // `iterations` receives the solver steps (x only).
    bool triangulate_x(double u, double v, double proj_x, Vec3& point,
                       int* iterations = nullptr) const;
    bool triangulate_xy(double u, double v, double proj_x, double proj_y, Vec3& point,
                        double* ray_gap_mm = nullptr) const;
    // One camera pixel (u, v) (in the image) by its ray in camera_rays(),
    // as reconstruct() finds it: for a few points of a scan without a
    // camera-size decode result.
    bool triangulate_pixel_x(int u, int v, double proj_x, Vec3& point) const;

private:
    StereoCalibration calibration_;
    SvOptions options_;
    Image<float> rays_;
    std::unique_ptr<ThreadPool> pool_;
};

// The mode a decode result allows for the requested one: automatic -> xy if
// both axes are decoded, else x. Throws std::invalid_argument naming the
// missing axis.
ReconstructAxes resolve_axes(const DecodeResult& decoded, ReconstructAxes requested);

} // namespace fpp::calib
