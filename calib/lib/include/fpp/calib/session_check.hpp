#pragma once
// Whether a calibration session is enough, and what to do if not: the
// trueness the session's calibration predicts (trueness.hpp), the image
// coverage of its corners, the spread of its tilts and depths, the poses
// that would shrink the depth scale's sigma most (in words a person at the
// board can follow), and a verdict against the user's target (default: 15
// um per 150 mm along depth, 1 sigma, at the session's middle depth).
//
// The session is calibrated exactly as `fpp-calib stereo` calibrates it
// (calibrate_session with the same options), so the figures are the ones
// that calibration would carry.

#include "fpp/calib/stereo_session.hpp"
#include "fpp/calib/trueness.hpp"
#include "fpp/image.hpp"

#include <string>
#include <vector>

namespace fpp::calib {

struct SessionCheckOptions {
    double target_mm = 0.015; // 1 sigma of a length along depth at the middle depth
    int suggestions = 3;      // poses suggested, best first
    // A session whose sigma is above this multiple of the target is too
    // weak for any target: more of the same poses would not get there.
    double too_weak_factor = 20;
    int coverage_cells_across = 8; // cells along the image's longer side
    // Throws std::invalid_argument naming the first bad field.
    void validate() const;
};

enum class SessionVerdict { enough, not_yet, too_weak };
const char* to_string(SessionVerdict verdict); // "enough", "not yet", "too weak"

struct SessionCheck {
    SessionVerdict verdict = SessionVerdict::too_weak;
    std::string reason; // one sentence: why the verdict
    double target_mm = 0;
    Trueness trueness; // the session's calibration's (unknown when too weak to compute)
    std::vector<PoseSuggestion> next;
    int poses_used = 0, poses_found = 0;
    // Corners per cell of the camera image (cell_px square, row-major from
    // the top left), over the poses used.
    Image<float> coverage;
    int coverage_cell_px = 0;
    double coverage_fraction = 0;              // of the cells holding a corner
    double min_tilt_deg = 0, max_tilt_deg = 0; // board normal against the optical axis
    // What a person reads: verdict, trueness so far, coverage, tilts and
    // depths, the next pose in words.
    std::string text() const;
};

// Checks a session calibrated by calibrate_session (with
// options.stereo.suggest_next_poses = check options' suggestions).
SessionCheck check_session(const SessionResult& session, const SessionCheckOptions& options = {});

// A session that cannot be calibrated at all (calibrate_session threw
// `why`): too weak, with the reason.
SessionCheck too_weak_session(const std::string& why, const SessionCheckOptions& options = {});

} // namespace fpp::calib
