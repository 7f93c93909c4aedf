#pragma once
// Least-squares fits of geometric elements to measured points, for the
// evaluation of reconstructions (plane, sphere, cylinder, ball-bar), and an
// exact nearest-neighbour index over 3D points.
//
// Units and frame: whatever the points are in (here camera frame, mm); every
// length below is in the points' unit.
//
// Every fit works in double precision on conditioned points: the centroid is
// subtracted and the coordinates are divided by their RMS distance from it,
// so that the normal equations stay well conditioned for a 1 m stand-off.
//   plane     orthogonal distance regression: SVD of the centred points; the
//             normal is the right singular vector of the smallest singular value.
//   sphere    algebraic fit (|p|^2 = 2 c.p + d, linear) as the start, then
//             Levenberg-Marquardt on the orthogonal distances |p - c| - r.
//   cylinder  start: the axis as the direction most orthogonal to the local
//             surface normals (PCA of neighbourhoods), plus the three principal
//             directions of the points as fall-backs; for each start axis a
//             circle fit of the points projected along it; then
//             Levenberg-Marquardt on (distance to axis) - r, re-linearised
//             about the current axis every step (Forbes' parametrisation), and
//             the start with the lowest RMS wins. Converges on the part of a
//             cylinder a scanner sees from one side (90-120 degrees of arc).
//   ball-bar  two spheres; the figure is the distance of their centres.
//
// Signed residuals: plane: distance along the normal, which points towards the
// camera centre (the origin), so positive = nearer the camera; sphere and
// cylinder: positive outside the surface (further from centre / axis).
//
// Optional robust mode: iterative rejection of points whose |residual| exceeds
// k times the RMS of the current inliers, refitting until the inlier set is
// stable (every point is re-tested each round, so a point may come back).
//
// Failures (too few points, non-finite coordinates, degenerate geometry such
// as collinear points for a plane, coplanar points for a sphere or a flat
// patch for a cylinder, no convergence) throw FitError with the reason; a fit
// never returns parameters it could not determine.

#include "fpp/lens_model.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace fpp::calib {

class FitError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct FitOptions {
    // Outlier rejection at reject_sigma x RMS; 0 = off (every point is used).
    double reject_sigma = 0;
    int max_rejection_rounds = 20;
    int max_iterations = 200; // Levenberg-Marquardt steps (sphere, cylinder)
};

// What every fit reports.
struct FitResiduals {
    std::vector<double> residuals;    // signed, one per input point (outliers included)
    std::vector<std::uint8_t> inlier; // 1 = used by the final fit
    std::size_t used = 0;             // points used by the final fit
    std::size_t rejected = 0;         // points rejected as outliers
    int rejection_rounds = 0;         // refits after rejections
    int iterations = 0;               // Levenberg-Marquardt steps of the final fit (0 for a plane)
    double rms = 0;                   // RMS of the used points' residuals
    double min = 0, max = 0;          // extreme signed residuals of the used points
    std::string message;              // one-line summary of the fit
};

struct PlaneFit {
    Vec3 point{};  // centroid of the used points (on the plane)
    Vec3 normal{}; // unit, pointing towards the origin (camera centre)
    FitResiduals fit;
};

struct SphereFit {
    Vec3 centre{};
    double radius = 0;
    FitResiduals fit;
};

struct CylinderFit {
    Vec3 axis_point{}; // the point of the axis nearest to the used points' centroid
    Vec3 axis{};       // unit direction
    double radius = 0;
    double arc_degrees = 0; // angle the used points span around the axis (<= 360)
    double length = 0;      // extent of the used points along the axis
    FitResiduals fit;
};

struct BallBarFit {
    SphereFit first, second;
    double distance = 0; // between the centres
    std::string message;
};

// Minimum number of points: plane 3, sphere 4, cylinder 5 (one per parameter).
PlaneFit fit_plane(std::span<const Vec3> points, const FitOptions& options = {});
SphereFit fit_sphere(std::span<const Vec3> points, const FitOptions& options = {});
CylinderFit fit_cylinder(std::span<const Vec3> points, const FitOptions& options = {});
// Both spheres' points given separately.
BallBarFit fit_ball_bar(std::span<const Vec3> first, std::span<const Vec3> second,
                        const FitOptions& options = {});
// One cloud holding both spheres (and possibly the bar between them): split
// into two clusters (2-means started at the extremes of the principal
// direction), then one sphere fit per cluster. `cluster` (optional) receives
// 0 or 1 per point. Residuals of the bar, if scanned, are large: use
// options.reject_sigma to reject them.
BallBarFit fit_ball_bar(std::span<const Vec3> points, const FitOptions& options = {},
                        std::vector<std::uint8_t>* cluster = nullptr);

// Exact nearest-neighbour search over a fixed set of 3D points (k-d tree,
// median splits). The points are copied.
class PointIndex {
public:
    explicit PointIndex(std::span<const Vec3> points);
    std::size_t size() const { return points_.size(); }
    // Index of the point nearest to `query` and its squared distance; the
    // index is size() when the set is empty.
    std::size_t nearest(const Vec3& query, double* squared_distance = nullptr) const;
    // The k nearest points as (squared distance, index), nearest first (fewer
    // if the set is smaller). `out` is reused (no allocation once it has
    // capacity k + 1).
    void nearest_k(const Vec3& query, std::size_t k,
                   std::vector<std::pair<double, std::size_t>>& out) const;

private:
    struct Node {
        std::uint32_t begin, end; // range in order_
        std::int32_t left = -1, right = -1;
        std::uint8_t axis = 0;
        double split = 0;
    };
    std::int32_t build(std::uint32_t begin, std::uint32_t end);
    void search_nearest(std::int32_t node, const Vec3& q, double& best, std::size_t& index) const;
    void search_k(std::int32_t node, const Vec3& q, std::size_t k,
                  std::vector<std::pair<double, std::size_t>>& heap) const;
    std::vector<Vec3> points_;
    std::vector<std::uint32_t> order_;
    std::vector<Node> nodes_;
};

} // namespace fpp::calib
