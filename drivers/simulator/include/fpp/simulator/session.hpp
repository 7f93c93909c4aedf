#pragma once
// Simulated calibration sessions: a board moved through the paper's
// calibration volume (~270 x 200 x 130 mm, board centres 400 to 560 mm from
// the camera), one capture set per pose, as a person would record them.
//
// Session folder layout (what `fpp-calib stereo` reads):
//   board.yaml          fpp-board/1 (kind checkerboard or plane)
//   pose-01/, pose-02/, ...   one capture set each (fpp-capture/1) with truth
//                             files; the board pose is recorded in the
//                             capture's metadata (board_pose: centre_mm,
//                             rotation row-major, board-local to camera frame)
//
// Board frame: x along the checkerboard's columns (inner corner i), y along
// its rows (corner j), z = normal pointing away from the camera when the board
// faces it. Inner corner (i, j) is at ((i - (cols-1)/2) s, (j - (rows-1)/2) s, 0)
// about the board centre (fpp::sim::Checkerboard).

#include "fpp/enum_names.hpp"
#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace fpp::sim {

enum class SessionKind { checkerboard, plane };
inline constexpr EnumName<SessionKind> kSessionKindNames[] = {
    {SessionKind::checkerboard, "checkerboard"}, {SessionKind::plane, "plane"}};

// The session checkerboard: 11 x 8 inner corners of 15 mm (12 x 9 squares,
// 180 x 135 mm) printed in the middle of a flat white board with a 120 mm
// margin (420 x 375 mm). The paper's board had 8 mm squares; 15 mm squares
// fill more of the ~270 x 200 mm field (more of the lens distortion is
// sampled) and still fit inside both fields at 400 mm when tilted by ~28
// degrees. The white margin fills the rest of the field, so that every pose
// also samples the projector and the per-pixel fits over most of the image
// (the camera-anchored hybrid calibration). 11 + 8 is odd, so the pattern is
// not symmetric under a 180-degree turn: the origin corner can be told by
// colour (the square diagonally outside inner corner (0, 0) is black).
CheckerboardSpec session_checkerboard();

struct SessionOptions {
    SessionKind kind = SessionKind::checkerboard;
    int poses = 15;
    std::uint64_t seed = 1; // pose jitter and sensor noise
    CheckerboardSpec board = session_checkerboard();
    double plane_width_mm = 520; // the white plane (kind plane)
    double plane_height_mm = 420;
    double plane_albedo = 0.85;
    double near_mm = 400; // board centre distances
    double far_mm = 560;
    double max_tilt_deg = 28;       // about the board's x and y axes
    double max_roll_deg = 8;        // about the board normal
    double max_plane_tilt_deg = 12; // kind plane
    // Pixels every checker corner keeps from the border of both images, for
    // a camera 1600 px wide (checkerboard_margin_px scales it to smaller
    // images: a binned camera sees the same margin in fewer pixels).
    double visibility_margin_px = 12;
};

// The board poses of a session (board-local to camera frame), deterministic
// for given options and rig. Checkerboard poses keep the whole pattern
// (every square plus a quarter of a square of white around it) inside the
// camera and the projector image with `visibility_margin_px` to spare;
// plane poses cover the whole camera field. Throws std::invalid_argument if
// a pose cannot be placed (a board too large for the rig's field).
std::vector<Pose> session_poses(const Rig& rig, const SessionOptions& options);

// The margin the checkerboard poses keep for this rig: visibility_margin_px
// scaled by the camera's width / 1600 (at most 1), at least 8 px (the
// corner finder's window).
double checkerboard_margin_px(const Rig& rig, const SessionOptions& options);

// Whether the whole checker pattern at `pose` (every square plus a quarter
// square of white around it) is inside both images with `margin_px` to spare,
// and faces both devices.
bool checkerboard_fully_visible(const Rig& rig, const CheckerboardSpec& board, const Pose& pose,
                                double margin_px);
// Whether a plane of the given size at `pose` covers the whole camera image.
bool plane_covers_camera(const Rig& rig, double width_mm, double height_mm, const Pose& pose);

// The scene of one pose.
Scene session_scene(const SessionOptions& options, const Pose& pose);

// board.yaml text for these options (fpp-board/1, with comments describing the board).
std::string session_board_yaml(const SessionOptions& options);

// The metadata recorded in pose k's capture (0-based): session_pose (k + 1)
// and board_pose (centre_mm, rotation row-major), YAML text.
std::string session_pose_metadata_yaml(int k, const Pose& pose);

// Folder name of pose k (0-based): "pose-01", "pose-02", ...
std::string session_pose_name(int k, int count);

// Progress: called after each pose is written (poses done, total).
using SessionProgress = std::function<void(int done, int total)>;

// Renders and writes a whole session into `folder`, which must not exist
// (IoError). Written into a temporary sibling folder renamed into place when
// complete: a failure leaves nothing behind. Throws std::invalid_argument for
// options out of range or poses that cannot be placed (before writing). Any
// sequence is rendered (a checkerboard session without phase in y is
// written; the stereo calibration then refuses it).
void write_session(const std::filesystem::path& folder, const Rig& rig, const Sequence& sequence,
                   const SessionOptions& options, const SessionProgress& progress = {});

} // namespace fpp::sim
