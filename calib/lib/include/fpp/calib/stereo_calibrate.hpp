#pragma once
// Stereo calibration of a camera and a projector (an inverse camera) from
// board corners seen by both, following the paper's SV model.
//
// Model: fpp::LensModel for both devices (fu, fv, cu, cv, skew, k1 k2 k3 p1 p2);
// board pose i maps board points to the camera frame, X_c = R_i X_b + t_i;
// the projector frame is X_p = R X_c + T (mm).
//
// Method: OpenCV initialises each device (cv::calibrateCamera, skew 0) and the
// camera-to-projector transform (cv::stereoCalibrate with the intrinsics
// fixed); then one Levenberg-Marquardt bundle adjustment refines everything
// together (both devices' intrinsics with skew, distortion, R, T and every
// board pose), minimising camera and projector reprojection errors in pixels
// through LensModel's skew-aware projection. Rotations are updated
// multiplicatively (R <- exp([w]x) R), the normal equations are scaled to
// unit diagonal, the Jacobian is by central differences, block-sparse in the
// board poses.
//
// RMS: sqrt(mean over points of |reprojection error|^2), px (OpenCV's figure).

#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <functional>
#include <string>
#include <vector>

namespace fpp::calib {

struct PoseObservations {
    std::string name;
    std::vector<Vec3> board;     // board frame, mm (z = 0 for a flat board)
    std::vector<Vec2> camera;    // camera px
    std::vector<Vec2> projector; // projector px; NaN where the projector coordinate failed
};

// Board frame -> camera frame: X_c = R X_b + t.
struct RigidPose {
    Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Vec3 t{0, 0, 0};
};

struct StereoOptions {
    bool skew = true;           // estimate skew for both devices (else fixed at 0)
    bool drop_outliers = false; // drop outlying poses and refine again
    // A pose is an outlier when its RMS (camera and projector together)
    // exceeds this multiple of the median pose RMS.
    double outlier_factor = 2.5;
    int max_iterations = 100;
    // Progress lines (stderr in the tool); may be empty.
    std::function<void(const std::string&)> progress;
};

struct StereoResult {
    // Intrinsics, R, T, overall and per-pose RMS (poses in input order, with
    // `used` false and a note for dropped outliers).
    StereoCalibration calibration;
    std::vector<RigidPose> board_poses; // per input pose
    // Per input pose and point: predicted - measured, px (NaN where unused).
    std::vector<std::vector<Vec2>> camera_residuals;
    std::vector<std::vector<Vec2>> projector_residuals;
    std::vector<int> outliers;      // input indices of poses flagged as outliers
    double initial_camera_rms = -1; // after OpenCV's initialisation (skew 0)
    double initial_projector_rms = -1;
    int iterations = 0;
    bool skew_estimated = true;
    // One-sigma uncertainties of the lens parameters (from the normal
    // equations and the residual variance); 0 for fixed parameters.
    LensModel camera_sigma;
    LensModel projector_sigma;
};

// Throws std::invalid_argument for fewer than 3 poses, a pose with fewer than
// 4 points, or mismatched point counts; std::runtime_error if OpenCV's
// initialisation fails.
StereoResult stereo_calibrate(const std::vector<PoseObservations>& poses, Size camera_size,
                              Size projector_size, const StereoOptions& options = {});

// Reprojection of board points through a calibration (camera and projector
// pixels), for reports and tests.
Vec2 project_camera(const StereoCalibration& calibration, const RigidPose& pose, const Vec3& board);
Vec2 project_projector(const StereoCalibration& calibration, const RigidPose& pose,
                       const Vec3& board);

// Rotation matrix <-> rotation vector (axis times angle, radians).
Mat3 rotation_from_vector(const Vec3& w);
Vec3 rotation_to_vector(const Mat3& R);

} // namespace fpp::calib
