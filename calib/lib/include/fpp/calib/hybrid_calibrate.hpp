#pragma once
// The paper's hybrid calibration: flat-board poses reconstructed by SV,
// corrected onto their best planes, then per camera pixel a cubic from phase
// to the corrected coordinates, stored as a coefficient table
// (fpp/coefficient_table.hpp).
//
// Conventions: camera frame, mm; phase = decoded projector column (projector
// px, vertical fringes, as the paper); planes n . X = d with |n| = 1 and
// n_z > 0 (facing away from the camera).
//
// Per pose (a session of `kind: plane` boards): decode, SV reconstruction
// with the projector column only (the paper's SV), a robust least-squares
// plane (orthogonal distances; points farther than max(outlier_sigmas x the
// robust sigma, outlier_floor_mm) are dropped and the plane refitted). A pose
// is rejected, with its reason, when too few camera pixels get a point or too
// many points lie off the plane (a box on the board, a bent board).
//
// Correction of each point onto its pose's plane, by model:
//   polynomial  the paper's: along the plane normal (perpendicular foot);
//               X, Y and Z each get a cubic in phase.
//   ray         along the pixel's camera ray (the camera's rays are the
//               better-known lines of an SV calibration: the corrected point
//               stays on its pixel's line of sight); only Z gets a cubic,
//               X = xn Z and Y = yn Z with the pixel's ray (xn, yn): half the
//               table.
//   rational    as ray, with Z = cubic / (1 + d t) (the default): along a
//               ray, depth is a ratio of linear functions of the projector
//               column for a pinhole projector, which a cubic follows only to
//               about 0.02 mm (0.06 mm at worst) over the paper's 130 mm deep
//               volume; the rational form follows it exactly and leaves the
//               cubic the lens distortion. On the virtual scanner the median
//               per-pixel fit RMS drops from 0.019 to 0.005 mm, and the
//               inclined plane's flatness from 0.014 (ray) and 0.015 mm
//               (polynomial) to 0.010 mm.
//
// Before the fits each pose's phase map is smoothed (phase_smoothing_radius):
// the board is flat and evenly white, so its phase varies smoothly over the
// image, while the phase noise of each pixel (about 0.03 px on the paper rig)
// would otherwise go straight into that pixel's cubic, which has only one
// sample per pose to average it. A local quadratic least-squares fit
// (separable Savitzky-Golay, window 2r + 1) keeps any quadratic variation of
// the phase exactly and divides the noise by about 7 at r = 7. Pixels whose
// window is not complete (image border, holes) keep their own phase. 0 = the
// paper's raw per-pixel samples.
//
// Per pixel the phase is normalised to t in [-1, 1] over the range of its
// poses, and the cubics are least-squares fits in double precision. A pixel
// gets no model (NaN centre in the table) when fewer than `min_poses` poses
// give it a point or its normal equations are ill-conditioned (samples
// bunched at one phase).

#include "fpp/calib/pixel_fit.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/decoder.hpp"
#include "fpp/image.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace fpp::calib {

struct HybridOptions {
    TableModel model = TableModel::rational;
    int min_poses = 6; // per pixel
    int phase_smoothing_radius = 7; // px; 0 = off: samples for a cubic (4 coefficients) with room to spare
    // Per pixel: largest ratio of the normal equations' largest to smallest
    // pivot (t normalised to [-1, 1]).
    double max_condition = 1e7;
    // Pose plane fit.
    double outlier_sigmas = 5;
    double outlier_floor_mm = 0.5;
    double max_outlier_fraction = 0.02; // more points off the plane: pose rejected
    double min_pose_coverage = 0.25;    // fraction of camera pixels with a point
    int min_usable_poses = 4;
    int tile_width = 32;
    int tile_height = 8;
    DecodeOptions decode;
    SvOptions sv;
    int threads = 0; // per-pixel fitting; 0 = all cores
    std::function<void(const std::string&)> progress;

    // Throws std::invalid_argument naming the first bad field.
    void validate() const;
};

struct HybridPose {
    std::string name; // folder name
    std::filesystem::path folder;
    bool usable = false;
    std::string skip_reason;
    std::size_t points = 0;   // SV points
    std::size_t outliers = 0; // points dropped from the plane fit
    BoardPlane plane;
    double plane_rms_mm = 0; // inliers, orthogonal
    double plane_max_mm = 0; // largest |distance| among inliers
    double distance_mm = 0;  // plane's depth on the optical axis, d / n_z
    double tilt_deg = 0;     // angle between the normal and the optical axis
    double seconds = 0;      // read, decode, SV and plane fit
};

struct HybridResult {
    CoefficientTable table;
    std::vector<HybridPose> poses;
    int usable_poses = 0;
    // Per camera pixel: fit RMS of X, Y, Z and the predicted depth sigma (mm;
    // NaN without a model; see PixelFit) and the number of poses that gave it
    // a sample.
    Image<float> rms_x, rms_y, rms_z, sigma_z;
    Image<std::uint16_t> pose_count;
    std::size_t pixels_modelled = 0;
    std::size_t pixels_too_few_poses = 0;
    std::size_t pixels_ill_conditioned = 0;
    double seconds_poses = 0, seconds_fit = 0, seconds_total = 0;

    // A few lines: model, poses used and rejected (with reasons), pixels
    // modelled, fit RMS percentiles, times.
    std::string summary() const;
};

// Calibrates from a session folder (board.yaml kind plane, one capture set per
// pose with phase along x). `calibration_hash` is stored in the table
// (fnv1a64 of the calibration file). Throws InputError naming the file and
// field for bad input (no session, wrong board kind, no x phase, sizes that
// differ from each other or from the calibration, fewer than
// min_usable_poses usable poses), std::invalid_argument for bad options.
HybridResult calibrate_hybrid(const std::filesystem::path& session,
                              const StereoCalibration& calibration,
                              std::uint64_t calibration_hash, const HybridOptions& options = {});

// The same for several models at once (options.model is ignored): the poses
// are read, decoded and reconstructed once, and each model is fitted to
// them; one result per model, in order. Throws std::invalid_argument for an
// empty list.
std::vector<HybridResult> calibrate_hybrid(const std::filesystem::path& session,
                                           const StereoCalibration& calibration,
                                           std::uint64_t calibration_hash,
                                           const HybridOptions& options,
                                           const std::vector<TableModel>& models);

// The robust plane of a pose's points (3-channel image, NaN = no point):
// points off the plane get NaN in `xyz` when `drop_outliers`. Returns false
// (plane untouched) with fewer than 3 points or a degenerate layout.
struct PlaneFitStats {
    std::size_t points = 0, outliers = 0;
    double rms_mm = 0, max_mm = 0;
};
bool fit_board_plane(Image<float>& xyz, const HybridOptions& options, BoardPlane& plane,
                     PlaneFitStats& stats, bool drop_outliers = true);

} // namespace fpp::calib
