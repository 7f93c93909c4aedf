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
// fixed); then a Levenberg-Marquardt bundle adjustment (analytic Jacobians,
// normal equations scaled to unit diagonal, rotations updated
// multiplicatively, R <- exp([w]x) R) refines, by `procedure`:
//   camera_first  (default) the camera alone from its corners (intrinsics
//                 with skew, distortion, correction grid, every board pose),
//                 then the projector with the camera and the poses held:
//                 its intrinsics, distortion, correction grid, R and T, from
//                 the corners' projector coordinates and the dense samples.
//                 Nothing the projector does can move the camera or the
//                 boards: the board poses are the camera's alone, right in
//                 absolute terms whatever defect the projector lens has.
//   joint         the paper's: both devices, R, T and the poses together,
//                 minimising camera and projector reprojection errors (dense
//                 samples unused). A projector defect outside the model then
//                 pulls the camera and the poses (depth, scale, tilt).
// Correction grids (correction_grid.hpp) are estimated when their size is
// given, regularised by second differences and a small ridge.
//
// RMS: sqrt(mean over points of |reprojection error|^2), px (OpenCV's figure),
// of the corners.

#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/time_split.hpp"
#include "fpp/calib/trueness.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace fpp::calib {

struct PoseObservations {
    std::string name;
    std::vector<Vec3> board;     // board frame, mm (z = 0 for a flat board)
    std::vector<Vec2> camera;    // camera px
    std::vector<Vec2> projector; // projector px; NaN where the projector coordinate failed
    // Dense samples of the board's flat white parts (camera_first only): a
    // camera pixel and the projector pixel decoded there. The board point
    // is where the pixel's camera ray meets the board's plane.
    std::vector<Vec2> dense_camera;
    std::vector<Vec2> dense_projector;
};

// Board frame -> camera frame: X_c = R X_b + t.
struct RigidPose {
    Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Vec3 t{0, 0, 0};
};

enum class StereoProcedure { camera_first, joint };
// "camera-first", "joint"; parse throws std::invalid_argument otherwise.
const char* to_string(StereoProcedure procedure);
StereoProcedure parse_stereo_procedure(const std::string& name);

// Control points of a correction grid (0 x 0: none).
struct GridSize {
    int columns = 0, rows = 0;
    bool empty() const { return columns == 0 && rows == 0; }
};

struct StereoOptions {
    StereoProcedure procedure = StereoProcedure::camera_first;
    GridSize camera_grid{12, 9};
    GridSize projector_grid{12, 8};
    // Weight of each squared second difference of a grid's control values
    // (px^-2, as the observations', which are weighted by 1 / their noise
    // variance): 1 / the variance of a lens defect's curvature at the grid's
    // spacing. The camera's grid, seen only at its corners, is held
    // stiffer than the projector's, which the dense samples see everywhere.
    // camera_grid_smoothness 0: chosen among camera_grid_smoothness_choices
    // by cross-validation over the poses (each fold's poses placed by a
    // camera calibrated without them; the smoothness whose camera model
    // reprojects them best, the stiffer one unless a softer one is 2 %
    // better): a defect-free lens keeps a stiff grid, which leaves the
    // camera's frame as well determined as the lens model alone does, and
    // a lens with a defect gets the freedom to follow it. While the softest
    // choice tried is the best, up to camera_grid_softer_steps choices ten
    // times softer each are tried after the list. Needs at least 6 poses,
    // else the first choice is used.
    double camera_grid_smoothness = 0;
    std::vector<double> camera_grid_smoothness_choices{1e4, 1e3, 1e2};
    int camera_grid_softer_steps = 4;
    double projector_grid_smoothness = 1e3;
    double grid_ridge = 1e-4;   // weight of each squared control value (px^-2)
    bool skew = true;           // estimate skew for both devices (else fixed at 0)
    bool drop_outliers = false; // drop outlying poses and refine again
    // A pose is an outlier when its RMS (camera and projector together)
    // exceeds this multiple of the median pose RMS.
    double outlier_factor = 2.5;
    int max_iterations = 100;
    // camera_first: after the camera's adjustment its focal lengths are
    // multiplied by this (its distortion and skew kept in the image) and the
    // boards placed again with the camera held, before the projector's
    // stages: a depth scale a certified artefact measured (fpp-calib
    // correct). 1: none.
    double camera_focal_scale = 1;
    // Board poses to suggest for the session's next capture, best first
    // (StereoResult::next_poses; session_advice.hpp); 0: none (a few
    // seconds for 30 poses).
    int suggest_next_poses = 0;
    // Threads of the adjustments (dense samples, cross-validation folds);
    // 0: all cores. The result does not depend on it.
    int threads = 0;

    // Throws std::invalid_argument naming the first bad field.
    void validate() const;
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
    // Dense samples (camera_first): per input pose, predicted - measured
    // projector px of each sample (NaN where unused), and their RMS.
    std::vector<std::vector<Vec2>> dense_residuals;
    double dense_rms = -1;
    int iterations = 0;
    bool skew_estimated = true;
    StereoProcedure procedure = StereoProcedure::camera_first;
    // The camera grid's smoothness used, and the cross-validation's
    // reprojection RMS (px) of each choice tried (empty when not chosen so).
    double camera_grid_smoothness = 0;
    std::vector<std::pair<double, double>> camera_grid_validation;
    // One-sigma uncertainties of the lens parameters (from the normal
    // equations and the residual variance); 0 for fixed parameters.
    LensModel camera_sigma;
    LensModel projector_sigma;
    // The predicted trueness over the image (its figures are in
    // calibration.trueness): trueness.hpp.
    TruenessMap trueness_map;
    // The poses that would shrink the depth scale's sigma most, best first
    // (StereoOptions::suggest_next_poses).
    std::vector<PoseSuggestion> next_poses;
    TimeSplit time_split; // initialisation, cross-validation, each adjustment
};

// Throws std::invalid_argument for fewer than 3 poses, a pose with fewer than
// 4 points, or mismatched point counts; std::runtime_error if OpenCV's
// initialisation fails.
StereoResult stereo_calibrate(const std::vector<PoseObservations>& poses, Size camera_size,
                              Size projector_size, const StereoOptions& options = {});

// OpenCV's initialisation, where every bundle adjustment starts whatever
// the options (skew 0): each device from its own points, then the
// camera-to-projector transform with their intrinsics held.
struct StereoStart {
    LensModel camera, projector;
    Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Vec3 T{0, 0, 0};
    std::vector<RigidPose> board_poses;         // per pose, placed by the camera
    double camera_rms = -1, projector_rms = -1; // OpenCV's reprojection RMS, px
};
// Throws as stereo_calibrate.
StereoStart initialise_stereo(const std::vector<PoseObservations>& poses, Size camera_size,
                              Size projector_size,
                              const std::function<void(const std::string&)>& progress = {});
// stereo_calibrate from a start of the same poses (calibrations of one
// session with different options share it): the same result.
StereoResult stereo_calibrate(const std::vector<PoseObservations>& poses, Size camera_size,
                              Size projector_size, const StereoOptions& options,
                              const StereoStart& start);

// Reprojection of board points through a calibration (camera and projector
// pixels), for reports and tests.
Vec2 project_camera(const StereoCalibration& calibration, const RigidPose& pose, const Vec3& board);
Vec2 project_projector(const StereoCalibration& calibration, const RigidPose& pose,
                       const Vec3& board);

// Rotation matrix <-> rotation vector (axis times angle, radians).
Mat3 rotation_from_vector(const Vec3& w);
Vec3 rotation_to_vector(const Mat3& R);

} // namespace fpp::calib
