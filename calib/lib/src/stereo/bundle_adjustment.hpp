#pragma once
// The stereo bundle adjustment behind stereo_calibrate (internal): a
// Levenberg-Marquardt over any subset of the camera's and projector's lens
// parameters, their correction grids, the camera-to-projector transform and
// the board poses, with analytic Jacobians accumulated straight into the
// normal equations (a correction grid touches 16 control points per
// observation, a pose its own observations).
//
// Conventions as stereo_calibrate.hpp: X_c = R_i X_b + t_i per board pose i,
// X_p = R X_c + T; rotations updated as R <- exp([w]x) R; residuals are
// predicted - measured, px.

#include "fpp/calib/correction_grid.hpp"
#include "fpp/calib/stereo_calibrate.hpp"
#include "fpp/parallel.hpp"

#include <Eigen/Dense>

#include <functional>
#include <string>
#include <vector>

namespace fpp::calib::detail {

constexpr int kLensParameters = 10; // fu fv cu cv skew k1 k2 p1 p2 k3

struct RigState {
    LensModel camera, projector;
    CorrectionGrid camera_grid, projector_grid; // empty: none
    Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Vec3 T{0, 0, 0};
    std::vector<RigidPose> poses;
};

// A checkerboard corner seen by the camera (and by the projector, when
// `projector` is finite).
struct CornerObservation {
    int pose = 0;
    Vec3 board{};
    Vec2 camera{};
    Vec2 projector{};
};

// A point of a board's bright parts at a known camera-frame position
// (placed by the camera: the ray of camera pixel `camera` meets pose
// `pose`'s plane) and the projector pixel decoded there. Used while the
// camera and the poses are held.
struct DenseObservation {
    Vec3 camera_point{};
    Vec2 projector{};
    double weight = 1;
    int pose = -1;
    Vec2 camera{};
};

struct FreeParameters {
    bool camera_lens = false, camera_grid = false;
    bool projector_lens = false, projector_grid = false;
    bool skew = true;    // the skew of each free lens
    bool stereo = false; // R, T
    bool poses = false;
    bool camera_observations = false, projector_observations = false;
    // Weight of each kind of observation (1 / its noise variance, px^-2):
    // camera corners, projector corners, dense samples. The grids'
    // regularisation weights are in the same units.
    double camera_weight = 1, projector_weight = 1, dense_weight = 1;
};

struct GridRegularisation {
    // Weight of each squared second difference of a grid's control values
    // (px^-2, the units of the observations' weights): 1 / the variance of
    // the curvature a lens defect is expected to have at the grid's spacing.
    double camera_smoothness = 1e4, projector_smoothness = 1e3;
    double ridge = 1e-4; // weight of each squared control value (px^-2)
};

struct AdjustmentOutcome {
    int iterations = 0;
    double data_cost = 0; // sum of weighted squared residuals at the solution
    int residuals = 0;    // residual rows (2 per observation)
    int parameters = 0;   // free parameters
    // Covariance of the free lens parameters per unit residual variance:
    // camera then projector, kLensParameters each (0 where fixed).
    std::array<double, 2 * kLensParameters> lens_variance{};
};

// Adjusts the free parameters of `state` in place. `pose_used[i]` false
// leaves pose i's observations out. Throws std::runtime_error if the normal
// equations cannot be solved at the start. With a pool, many observations
// (dense samples) are evaluated on its threads, to the same result.
AdjustmentOutcome adjust(RigState& state, const std::vector<CornerObservation>& corners,
                         const std::vector<DenseObservation>& dense,
                         const std::vector<bool>& pose_used, const FreeParameters& free,
                         const GridRegularisation& regularisation, int max_iterations,
                         const std::function<void(const std::string&)>& progress,
                         ThreadPool* pool = nullptr);

// The cost (weighted squared residuals and regularisation) at `state` and
// its gradient with respect to the free parameters, g = J^T W r (half the
// cost's derivative), in the adjustment's parameter order; with
// apply_increment, what the tests check the analytic Jacobians with.
struct Linearisation {
    double cost = 0;
    std::vector<double> gradient;
};
// The grids' gauge (the fields they must not hold) comes from `start`'s
// lenses, as in an adjustment that started there (`state` when null).
Linearisation linearise(const RigState& state, const std::vector<CornerObservation>& corners,
                        const std::vector<DenseObservation>& dense,
                        const std::vector<bool>& pose_used, const FreeParameters& free,
                        const GridRegularisation& regularisation, const RigState* start = nullptr);
// The normal equations at `state`, without a step: A = J^T W J plus the
// grids' regularisation (both triangles) and g = J^T W r + the
// regularisation's gradient, over the free parameters in the adjustment's
// column order; `full_index[c]`: column c's place in the full order
// (full_order()). Throws std::runtime_error when a point lies behind a
// device. The grids' gauge comes from `state`'s lenses.
struct NormalEquations {
    Eigen::MatrixXd A;
    Eigen::VectorXd g;
    std::vector<int> full_index;
    double data_cost = 0; // weighted squared residuals (no regularisation)
    int residuals = 0;    // residual rows
};
NormalEquations normal_equations(const RigState& state,
                                 const std::vector<CornerObservation>& corners,
                                 const std::vector<DenseObservation>& dense,
                                 const std::vector<bool>& pose_used, const FreeParameters& free,
                                 const GridRegularisation& regularisation,
                                 ThreadPool* pool = nullptr);

// Where each block starts in the full order of every parameter the
// adjustment knows (a free set's columns are a subsequence of it): lenses in
// kLensParameters order, R T as (w, t), grids as (du, dv) per control
// point, then 6 per board pose.
struct FullOrder {
    int camera_lens = 0, projector_lens = 0, stereo = 0, camera_grid = 0, projector_grid = 0;
    int poses = 0, size = 0;
};
FullOrder full_order(const RigState& state);

// The fields a correction grid must not hold, one per row, each a unit
// vector of (du, dv) per control point: constant and linear displacements
// (principal point, focal lengths, skew, a turn about the optical axis), the
// image motion of a small turn about the x or y axis, and the distortion
// terms' own fields, all through `lens`. Empty for an empty grid. The
// adjustment keeps each grid orthogonal to them (grid_gauge.cpp).
std::vector<std::vector<Vec2>> gauge_fields(const CorrectionGrid& grid, const LensModel& lens);

// The calibration a state holds: its lenses, grids, R and T, with the
// sizes given (the poses are not part of it).
inline StereoCalibration calibration_of(const RigState& s, Size camera_size = {},
                                        Size projector_size = {}) {
    StereoCalibration c;
    c.camera_size = camera_size;
    c.projector_size = projector_size;
    c.camera = s.camera;
    c.projector = s.projector;
    c.camera_correction = s.camera_grid;
    c.projector_correction = s.projector_grid;
    c.R = s.R;
    c.T = s.T;
    return c;
}

// Adds `step` (free parameters, the same order) to `state`.
void apply_increment(RigState& state, const std::vector<bool>& pose_used,
                     const FreeParameters& free, const std::vector<double>& step);

// Projection through a lens and its correction grid, with derivatives.
struct Projection {
    Vec2 pixel{};
    double d_point[2][3]{};              // d pixel / d point (device frame, mm)
    double d_lens[2][kLensParameters]{}; // d pixel / d lens parameters
    int grid_index[CorrectionGrid::kSupport]{};
    double grid_weight[CorrectionGrid::kSupport]{}; // d pixel_u / d du_k = d pixel_v / d dv_k
};
// False for a point not in front of the device (Z <= 0).
bool project_with_derivatives(const LensModel& lens, const CorrectionGrid& grid, const Vec3& point,
                              Projection& out);

} // namespace fpp::calib::detail
