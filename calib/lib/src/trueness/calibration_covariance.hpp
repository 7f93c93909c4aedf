#pragma once
// The covariance of a stereo calibration's parameters (internal to
// stereo_calibrate): what the session's corners and dense samples leave
// unknown, the board poses marginalised, for the estimator the procedure
// really is.
//
//   joint         one adjustment of everything: Sigma = s A^-1 (A the
//                 normal matrix with the grids' regularisation, s the
//                 residual variance per degree of freedom; the weights are
//                 1 / each observation kind's noise variance).
//   camera_first  two adjustments. The camera's (lens, grid, poses) from its
//                 corners: Sigma_1 = s_1 A_1^-1. The projector's (lens, grid,
//                 R, T) from its corners and the dense samples with the
//                 camera and the poses held: its own noise s_2 A_2^-1, and
//                 the camera stage's errors carried through the board points
//                 it is given (its corners move with the poses, the dense
//                 samples with the camera's rays and the boards' planes):
//                 d theta_2 = -A_2^-1 M d theta_1 with M = d g_2 / d theta_1
//                 (projector_response below), so
//                 Sigma_2 = s_2 A_2^-1 + B Sigma_1 B^T and Sigma_21 =
//                 -B Sigma_1 (B = A_2^-1 M).
//
// The result is over the calibration's parameters in bundle_adjustment.hpp's
// full order up to the poses (camera lens, projector lens, R T as (w, t),
// camera grid, projector grid); a fixed parameter's row and column are 0.
// Units: px, px per unit of distortion term, rad, mm.

#include "stereo/bundle_adjustment.hpp"

#include <Eigen/Dense>

#include <vector>

namespace fpp::calib::detail {

// Places each dense sample's camera point where its camera pixel's ray
// (through s's camera and grid) meets its pose's board plane; a sample
// whose ray cannot be found or meets the plane behind the camera keeps its
// point and gives false in `placed` (when given).
void place_dense_points(const RigState& s, std::vector<DenseObservation>& dense,
                        std::vector<bool>* placed = nullptr);

// The covariance and what it is made of: the adjustment that holds the
// board poses (the camera's, or the joint one) with its normal matrix, and
// how its parameters carry into the calibration's, so that a pose not yet
// taken can be weighed by what it would add (session_advice.hpp):
//   sigma = transfer (s A^-1) transfer^T + own.
struct CalibrationCovariance {
    Eigen::MatrixXd sigma;             // over the calibration's parameters (order above)
    FreeParameters pose_stage;         // what the adjustment holding the poses held free
    Eigen::MatrixXd pose_stage_normal; // its A (regularisation included)
    double pose_stage_variance = 1;    // its s
    std::vector<int> pose_stage_index; // its columns' full-order indices
    Eigen::MatrixXd transfer;          // d calibration / d its parameters (rows: sigma's order)
    Eigen::MatrixXd own;               // the projector stage's own noise (camera_first), else 0
};

CalibrationCovariance joint_covariance(const RigState& s,
                                       const std::vector<CornerObservation>& corners,
                                       const std::vector<bool>& pose_used,
                                       const FreeParameters& free,
                                       const GridRegularisation& regularisation, ThreadPool* pool);

// `dense` as the projector stage used them (placed at s).
CalibrationCovariance
camera_first_covariance(const RigState& s, const std::vector<CornerObservation>& corners,
                        const std::vector<DenseObservation>& dense,
                        const std::vector<bool>& pose_used, const FreeParameters& camera_stage,
                        const FreeParameters& projector_stage,
                        const GridRegularisation& regularisation, ThreadPool* pool);

// M = d g_2 / d theta_1: how the projector stage's gradient moves with the
// camera stage's parameters (its corners' board points with the poses, its
// dense samples with the camera's rays and the boards' planes), from the
// analytic derivatives, second-order terms left out as the normal equations
// leave them; rows and columns in the stages' column orders (their
// NormalEquations::full_index).
Eigen::MatrixXd projector_response(const RigState& s, const std::vector<CornerObservation>& corners,
                                   const std::vector<DenseObservation>& dense,
                                   const std::vector<bool>& pose_used,
                                   const std::vector<int>& camera_index,
                                   const std::vector<int>& projector_index,
                                   const FreeParameters& projector_stage);
// The same by central differences of the projector stage's gradient, one
// step per camera-stage column (slow: two passes over every observation
// per column; what the tests check projector_response with).
Eigen::MatrixXd projector_response_by_differences(
    const RigState& s, const std::vector<CornerObservation>& corners,
    const std::vector<DenseObservation>& dense, const std::vector<bool>& pose_used,
    const FreeParameters& camera_stage, const FreeParameters& projector_stage,
    const GridRegularisation& regularisation, const std::vector<double>& steps);

// The free set that opens every calibration parameter (each block up to
// the poses, skew too): its columns are the full order's indices, so
// apply_increment with it adds a step in the covariance's order.
FreeParameters calibration_parameters();

} // namespace fpp::calib::detail
