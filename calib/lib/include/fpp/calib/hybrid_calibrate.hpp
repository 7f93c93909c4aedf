#pragma once
// Hybrid calibration: board poses whose planes are known, then per camera
// pixel a model from phase to X, Y, Z (pixel_fit.hpp), stored as a
// coefficient table (fpp/coefficient_table.hpp). The board kind in the
// session's board.yaml decides the procedure:
//
// kind: checkerboard (camera-anchored, the default of the tools): each
//   pose's plane comes from the camera alone: its corners and the
//   calibration's camera model (intrinsics and correction grid, which the
//   camera-first stereo procedure estimates from the camera's corners only)
//   place the board. Samples where each pixel's ray meets that plane, on the
//   board's bright parts (board_samples.hpp: white squares and margin, away
//   from dark/bright edges, low modulation dropped), smoothed on each pose
//   where the smoothing window holds no dark square; samples further than
//   max_sample_deviation_px from the stereo model's column are not on the
//   board (a wall behind it) and are dropped. The stereo model then adds
//   samples along each pixel's ray over the depth range its boards reached
//   (`samples`): the poses between the boards. One session of about 30
//   checkerboard poses with fringes in x and y thus gives the stereo
//   calibration and the table. A pose is rejected, with its reason, when its
//   board is not found, the projector lights too little of it, or too few
//   of its pixels give a sample.
//
// kind: plane (the paper's procedure): flat white boards reconstructed by SV
//   with the calibration, each corrected onto its own best plane. That plane
//   carries whatever depth offset and tilt the stereo calibration has.
//   Per pose: decode, SV reconstruction with the projector column only (the
//   paper's SV), a robust least-squares plane (orthogonal distances; points
//   farther than max(outlier_sigmas x the robust sigma, outlier_floor_mm)
//   are dropped and the plane refitted). A pose is rejected, with its reason,
//   when too few camera pixels get a point or too many points lie off the
//   plane (a box on the board, a bent board).
//
// Conventions: camera frame, mm; phase = decoded projector column (projector
// px, vertical fringes, as the paper); planes n . X = d with |n| = 1 and
// n_z > 0 (facing away from the camera).
//
// Correction of each point onto its pose's plane, by model:
//   polynomial  the paper's: along the plane normal (perpendicular foot) for
//               plane sessions, along the ray for checkerboard sessions; X,
//               Y and Z each get a cubic in phase.
//   ray         along the pixel's camera ray (the corrected point stays on
//               its pixel's line of sight); only Z gets a cubic, X = xn Z and
//               Y = yn Z with the pixel's ray (xn, yn): half the table.
//   rational    as ray, with Z = cubic / (1 + d t) (the default): along a
//               ray, depth is a ratio of linear functions of the projector
//               column for a pinhole projector, which a cubic follows only to
//               about 0.02 mm (0.06 mm at worst) over the paper's 130 mm deep
//               volume; the rational form follows it exactly and leaves the
//               cubic the lens distortion.
//
// Before the fits each pose's phase map is smoothed (phase_smoothing_radius,
// a local quadratic fit; 0 = the paper's raw per-pixel samples). Per pixel
// the phase is normalised to t in [-1, 1] over the range of its samples; a
// pixel gets no model (NaN centre in the table) when fewer than `min_poses`
// poses give it a sample or its fit is ill-conditioned; a phase outside the
// calibrated range gives no point (no extrapolation).

#include "fpp/calib/board_samples.hpp"
#include "fpp/calib/corners.hpp"
#include "fpp/calib/pixel_fit.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/calib/time_split.hpp"
#include "fpp/capture_set.hpp"
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

struct StereoSessionOptions; // fpp/calib/stereo_session.hpp

// What a checkerboard session's tables are fitted to.
enum class HybridSamples {
    boards_and_model, // the boards' samples and the stereo model's between them (default)
    boards,           // the boards' samples alone
    model,            // the stereo model's samples alone, over the boards' depth range
};
// "boards+model", "boards", "model"; parse throws std::invalid_argument otherwise.
const char* to_string(HybridSamples samples);
HybridSamples parse_hybrid_samples(const std::string& name);

struct HybridOptions {
    TableModel model = TableModel::rational;
    int min_poses = 6; // per pixel
    int phase_smoothing_radius =
        7; // px; 0 = off: samples for a cubic (4 coefficients) with room to spare
    // Per pixel: largest ratio of the normal equations' largest to smallest
    // pivot (t normalised to [-1, 1]).
    double max_condition = 1e7;
    // Pose plane fit.
    double outlier_sigmas = 5;
    double outlier_floor_mm = 0.5;
    double max_outlier_fraction = 0.02; // more points off the plane: pose rejected
    double min_pose_coverage = 0.25;    // fraction of camera pixels with a point
    int min_usable_poses = 4;
    // Checkerboard sessions.
    HybridSamples samples = HybridSamples::boards_and_model;
    // Board samples a pixel needs when the stereo model's samples are
    // fitted too (min_poses when the boards' alone are): enough to show
    // that the boards reached the pixel and over which depths.
    int min_board_samples = 3;
    int model_samples = 8; // per pixel, evenly over its boards' depth range
    // The rational model's range extended by this on each side: the stereo
    // model is a model of rays, as good beyond the boards' depths as between
    // them (unlike beyond the projector pixels they lit), and a pixel at the
    // edge of the image saw the boards over a narrower range of depths than
    // the volume they spanned. The cubic models (polynomial, ray) keep to
    // the boards' range: a cubic in the column cannot follow depth over a
    // wider one.
    double model_depth_margin_mm = 60;
    BrightBoardOptions bright;
    double max_sample_deviation_px = 1.0; // from the stereo model's column: not on the board
    double min_lit_fraction = 0.5; // of the board's white squares' area decoded, else rejected
    double square_size_tolerance = 0.002; // relative, against the calibration's board
    int tile_width = 32;
    int tile_height = 8;
    DecodeOptions decode;
    SvOptions sv;
    int threads = 0; // per-pixel fitting; 0 = all cores
    std::function<void(const std::string&)> progress;

    // Throws std::invalid_argument naming the first bad field.
    void validate() const;
    // The margin a model's stereo-model samples reach beyond a pixel's boards
    // (mm): model_depth_margin_mm for the rational model, 0 for the cubics.
    double depth_margin_mm(TableModel fitted) const {
        return fitted == TableModel::rational ? model_depth_margin_mm : 0.0;
    }
};

struct HybridPose {
    std::string name; // folder name
    std::filesystem::path folder;
    bool usable = false;
    std::string skip_reason;
    std::size_t points = 0;   // SV points
    std::size_t outliers = 0; // points dropped from the plane fit
    BoardPlane plane;         // the plane the samples are put on
    // Plane sessions: inliers about their own plane, orthogonal. Checkerboard
    // sessions: the SV points of the board's bright parts (every 4th row and
    // column) about the camera's plane (how far the stereo model is from
    // where the camera puts it).
    double plane_rms_mm = 0;
    double plane_max_mm = 0; // largest |distance| among those points
    // Checkerboard sessions: the board's camera-only placement against the
    // stereo model's best plane through its SV points: the SV plane's
    // signed distance from the board's centre along the normal (mm, > 0:
    // SV puts the board further away) and the angle between the normals.
    double sv_offset_mm = 0;
    double sv_angle_deg = 0;
    double corner_rms_px = 0; // the camera's reprojection RMS of the corners at this pose
    double lit_fraction = 0;  // of the board's white squares' area decoded (half the squares')
    std::size_t samples = 0;  // pixels given a sample
    double distance_mm = 0;   // plane's depth on the optical axis, d / n_z
    double tilt_deg = 0;      // angle between the normal and the optical axis
    double seconds = 0;       // read, decode, SV and plane fit
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
    TimeSplit time_split; // reading, decoding, corners, ..., per-pixel fits
    BoardDescription::Kind board = BoardDescription::Kind::plane; // the procedure used
    HybridSamples samples = HybridSamples::boards; // what was fitted (checkerboard sessions)
    // The calibration's predicted trueness (trueness.hpp), also in the
    // table's header; unknown when the calibration has none.
    Trueness trueness;

    // A few lines: model, poses used and rejected (with reasons), pixels
    // modelled, fit RMS percentiles, times.
    std::string summary() const;
};

// Calibrates from a session folder (board.yaml and one capture set per pose
// with phase along x; the board kind decides the procedure).
// `calibration_hash` is stored in the table (fnv1a64 of the calibration
// file). Throws InputError naming the file and field for bad input (no
// session, no x phase, sizes that differ from each other or from the
// calibration, a square size that differs from the calibration's board,
// fewer than min_usable_poses usable poses), std::invalid_argument for bad
// options.
HybridResult calibrate_hybrid(const std::filesystem::path& session,
                              const StereoCalibration& calibration, std::uint64_t calibration_hash,
                              const HybridOptions& options = {});

// The same for several models at once (options.model is ignored): the poses
// are read, decoded and reconstructed once, and each model is fitted to
// them; one result per model, in order. Throws std::invalid_argument for an
// empty list.
std::vector<HybridResult> calibrate_hybrid(const std::filesystem::path& session,
                                           const StereoCalibration& calibration,
                                           std::uint64_t calibration_hash,
                                           const HybridOptions& options,
                                           const std::vector<TableModel>& models);

// What a checkerboard pose gives the table before any calibration is known:
// the board's corners, how much of its squares the projector lights, and
// the projector column on its bright parts. The stereo calibration of the
// same session can keep them as it reads each pose
// (StereoSessionOptions::on_pose), so that stereo and table together read,
// decode and search every pose once (`fpp-calib calibrate`).
struct BoardView {
    CheckerboardCorners corners; // found false: corners.failure says why
    double lit_fraction = 0;     // of the board's squares' area decoded (0 when not found)
    Image<float> bright_column;  // proj_x on the board's bright parts, NaN elsewhere
};

// The view of a pose from its decoded maps (x axis, with modulation) and
// the corners found on it (columns x rows inner corners).
BoardView observe_board(const DecodeResult& decoded, const CheckerboardCorners& corners,
                        int columns, int rows, const HybridOptions& options);

// Sets stereo.on_pose so that calibrate_session(session, stereo) fills
// `views` (sized here to the session's poses) with each board's view for
// `hybrid`'s options. Throws InputError as read_session_folder for a session
// that is not a checkerboard session with phase in x and y.
void keep_board_views(const std::filesystem::path& session, const HybridOptions& hybrid,
                      StereoSessionOptions& stereo, std::vector<BoardView>& views);

// calibrate_hybrid for a checkerboard session whose poses were already
// seen: `views` holds one per pose folder, in the session's order, made with
// the same options. Reads no frames. Throws InputError as calibrate_hybrid
// (and for a session of another board kind), std::invalid_argument when
// the views do not match the session's poses in number or size.
std::vector<HybridResult>
calibrate_hybrid(const std::filesystem::path& session, const StereoCalibration& calibration,
                 std::uint64_t calibration_hash, const HybridOptions& options,
                 const std::vector<TableModel>& models, const std::vector<BoardView>& views);

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
