#pragma once
// The calibration's covariance carried to lengths (internal to
// stereo_calibrate; see fpp/calib/trueness.hpp for what the figures mean).
// Sensitivities by central differences of the triangulated length at 0.1
// sigma of each parameter; sigma^2 = g^T Sigma g.

#include "fpp/calib/trueness.hpp"
#include "stereo/bundle_adjustment.hpp"

#include <Eigen/Dense>

#include <vector>

namespace fpp::calib::detail {

// `covariance` over the calibration's parameters (calibration_covariance.hpp's
// order) of the calibration in `s` (its lenses, grids, R, T; the poses are
// not used); `camera_size` for the map.
struct TruenessInputs {
    const RigState* state = nullptr;
    const Eigen::MatrixXd* covariance = nullptr;
    Size camera_size;
    SessionDepths depths;
    double length_mm = 150;
    int map_cells_across = 16; // cells along the image's longer side
    // When given: d (length along depth at the middle depth) / d each
    // calibration parameter (covariance order; 0 where it has no variance).
    Eigen::VectorXd* middle_depth_gradient = nullptr;
};
Trueness predict_trueness(const TruenessInputs& in, TruenessMap* map = nullptr);

// The depths of the used poses' corners (camera Z).
SessionDepths session_depths(const RigState& s, const std::vector<CornerObservation>& corners,
                             const std::vector<bool>& pose_used);

} // namespace fpp::calib::detail
