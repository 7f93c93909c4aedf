#pragma once
// What `stereo`, `hybrid` and `calibrate` check before the work and write
// after it, shared so that the one-command calibration writes exactly what
// the two commands write.

#include "fpp/calib/held_out_check.hpp"
#include "fpp/calib/hybrid_calibrate.hpp"
#include "fpp/calib/stereo_session.hpp"

#include <filesystem>
#include <string>

namespace fpp::calib {

// Throws InputError when `out` is a folder (`option` names the file it
// should be, e.g. "--out names the calibration file to write") or when
// `report` (may be empty) exists and is not a report of `what`.
void check_output_file(const std::filesystem::path& out, const std::string& option);
void check_report_folder(const std::string& report, const std::string& what);

// The calibration a session gave, as its file holds it: every pose of the
// session in order, skipped ones with their reason.
StereoCalibration session_calibration(const SessionResult& result);

// The stereo calibration file (every pose of the session in order, skipped
// ones with their reason), the report when asked for, and the summary on
// stdout (times on stderr).
void write_stereo_outputs(const SessionResult& result, const std::filesystem::path& out,
                          const std::string& report, const HeldOutCheck* held_out);

// The table, the report when asked for, and the summary on stdout.
void write_hybrid_outputs(const HybridResult& result, const std::filesystem::path& out,
                          const std::string& report);

} // namespace fpp::calib
