#pragma once
// A whole stereo calibration from a session folder: board.yaml (kind
// checkerboard) and one capture set per pose (any sub-folder holding
// capture.yaml, in name order).
//
// Per pose: decode (fpp::decode), corner texture (white frame, else the
// phase frames), checkerboard corners, projector coordinates of the corners
// (all three methods are measured; `method` feeds the calibration), then
// stereo_calibrate over the usable poses. A pose whose board is not found or
// whose corners have too few projector coordinates is skipped with its
// reason (progress and SessionResult), never silently.
//
// Bad input throws fpp::InputError naming the file and what is wrong, before
// anything is written: no board.yaml or not a checkerboard, no capture sets,
// capture sets of different camera or projector sizes, a sequence without
// phase on x or y (both projector coordinates are needed), a capture that
// cannot be read or decoded, fewer than 3 usable poses.

#include "fpp/calib/board_samples.hpp"
#include "fpp/calib/corner_projector.hpp"
#include "fpp/calib/corners.hpp"
#include "fpp/calib/stereo_calibrate.hpp"
#include "fpp/calib/time_split.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/error.hpp"

#include <array>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace fpp::calib {

constexpr int kCornerMethods = 3; // indexed by static_cast<int>(CornerMethod)

struct StereoSessionOptions {
    ProjectorCornerOptions corners; // corners.method feeds the calibration
    CornerFinderOptions finder;
    StereoOptions stereo; // skew, outliers; progress is set from `progress`
    // Also calibrate with the other skew setting, for the report (on its own
    // thread alongside: about 6 s of CPU at full size, 30 poses).
    bool compare_skew = false;
    // For captures with the simulator's truth, also find the corners'
    // projector coordinates by the other methods and measure every method
    // against the truth (the report's comparison: about 4.7 s of CPU at
    // full size, 30 poses). Real captures have no truth and skip it anyway.
    bool compare_corner_methods = false;
    DecodeOptions decode;
    // A pose needs projector coordinates for at least this fraction of its corners.
    double min_projector_corner_fraction = 0.5;
    // Dense samples of the boards' bright parts for the projector (camera-first
    // procedure): one every `dense_step_px` pixels (0: a step giving about
    // 8000 grid points per pose) where `bright` keeps the pixel.
    bool dense_samples = true;
    int dense_step_px = 0;
    BrightBoardOptions bright;
    std::function<void(const std::string&)> progress;
    // Called once a pose's board has been searched, with its index among
    // the session's poses, what it decoded and the corners (found or not),
    // on the thread processing it (poses run in parallel); may be empty.
    // fpp-calib calibrate keeps the table's view of each board this way.
    std::function<void(int pose, const DecodeResult&, const CheckerboardCorners&)> on_pose;
};

struct SessionPose {
    std::string name; // folder name
    std::filesystem::path folder;
    bool usable = false;
    std::string skip_reason; // why not usable
    CheckerboardCorners corners;
    // Projector coordinates of the corners by each method: the options'
    // method always, the others only with compare_corner_methods for
    // captures with the simulator's truth (empty otherwise).
    std::array<ProjectorCorners, kCornerMethods> projector;
    // RMS error of each method against the simulator's truth_proj at the
    // detected camera corners (projector px), when the other methods ran.
    std::array<double, kCornerMethods> truth_rms{-1, -1, -1};
    int truth_points = 0;
    Image<std::uint8_t> texture; // 8-bit view of the corner texture (report figures)
    double decode_seconds = 0;
    double corner_seconds = 0;
};

struct SessionResult {
    std::filesystem::path folder;
    BoardDescription board;
    Size camera_size;
    Size projector_size;
    std::vector<SessionPose> poses;             // every capture set found
    std::vector<int> calibrated;                // indices into poses fed to the calibration
    std::vector<PoseObservations> observations; // what each of them fed it, in that order
    StereoResult stereo;                        // with options.stereo.skew
    std::optional<StereoResult> other_skew;     // with the other skew setting (compare_skew)
    CornerMethod method = CornerMethod::poly;
    double seconds_decode = 0, seconds_corners = 0, seconds_calibration = 0, seconds_total = 0;
    TimeSplit time_split; // reading, decoding, corners, ..., the calibration's stages
};

// Fewer than 3 usable poses: the session cannot be calibrated yet (an
// InputError naming the session folder, with why each pose was skipped).
class TooFewPosesError : public InputError {
public:
    TooFewPosesError(const std::filesystem::path& session, const std::string& message)
        : InputError(session, "", message) {}
};

SessionResult calibrate_session(const std::filesystem::path& session,
                                const StereoSessionOptions& options = {});

// Board points of a columns x rows checkerboard, ordering of corners.hpp, mm.
std::vector<Vec3> checkerboard_points(int columns, int rows, double square_size);

} // namespace fpp::calib
