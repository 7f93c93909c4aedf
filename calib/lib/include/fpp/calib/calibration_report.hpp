#pragma once
// Report of a stereo calibration session: summary.md (Markdown) and PNG
// figures (8-bit, OpenCV drawing):
//   corners-<pose>.png      the corner texture with the detected corners, the
//                           board origin (red) and its i (red) / j (green) axes
//   residuals-camera.png    reprojection residual vectors per corner, magnified,
//   residuals-projector.png one colour per pose, on the device's image
//   pose-rms.png            per-pose camera and projector RMS bars

#include "fpp/calib/held_out_check.hpp"
#include "fpp/calib/report_folder.hpp"
#include "fpp/calib/stereo_session.hpp"

#include <filesystem>
#include <string>

namespace fpp::calib {

// The Markdown summary (also what the tool prints), with the held-out
// check when given.
std::string calibration_summary(const SessionResult& result,
                                const HeldOutCheck* held_out = nullptr);

// Writes the report folder as a whole (temporary folder renamed into place;
// an earlier report there is replaced). Throws IoError, or InputError if the
// folder exists and is not a report.
void write_calibration_report(const std::filesystem::path& folder, const SessionResult& result,
                              const HeldOutCheck* held_out = nullptr);

// Rotation matrix -> Euler angles in degrees (a, b, c) with R = Rz(c) Ry(b) Rx(a).
Vec3 euler_deg_from_rotation(const Mat3& R);

} // namespace fpp::calib
