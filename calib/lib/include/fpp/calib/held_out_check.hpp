#pragma once
// Absolute accuracy of a stereo calibration on poses it did not see: each
// pose of a checkerboard session is left out in turn, the pair is calibrated
// from the others (the same procedure and options), and the left-out board's
// corners are measured with that calibration: triangulated from their camera
// pixels and the projector coordinates decoded there (SV with x and y). The
// board's true geometry is known (square size x corner index), so the
// measured corners are compared with it:
//   - fit RMS: the measured corners against the board placed by the best
//     rigid transform (no scale): the 3D error of a measurement in absolute
//     terms, less the board's unknown pose;
//   - scale error: the best similarity transform's scale - 1 (the relative
//     error of every length);
//   - length error: |measured - true| distance of every pair of corners at
//     least half the board's diagonal apart (VDI/VDE 2634-2 style): the RMS and
//     the largest.
// Conventions: camera frame, mm.

#include "fpp/calib/stereo_session.hpp"

#include <string>
#include <vector>

namespace fpp::calib {

struct HeldOutPose {
    std::string name;
    int corners = 0;          // measured (triangulated) corners
    double fit_rms_mm = 0;    // rigid fit of the board to them
    double scale_error = 0;   // similarity scale - 1
    double length_rms_mm = 0; // over the corner pairs
    double length_max_mm = 0; // largest |error|
    double distance_mm = 0;   // the board's centre from the camera
};

struct HeldOutCheck {
    std::vector<HeldOutPose> poses;
    double fit_rms_mm = 0;    // over every held-out corner
    double length_rms_mm = 0; // over every pair
    double length_max_mm = 0;
    double scale_error_rms = 0;
    double seconds = 0;
    std::string summary() const; // a few lines
};

// `session`: a calibrated session (calibrate_session), at least 4 poses
// calibrated. Throws std::invalid_argument otherwise.
HeldOutCheck check_held_out(const SessionResult& session, const StereoSessionOptions& options);

} // namespace fpp::calib
