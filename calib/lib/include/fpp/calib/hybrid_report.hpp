#pragma once
// Report of a hybrid calibration: summary.md (Markdown) and PNG figures:
//   fit-rms-x.png, fit-rms-y.png, fit-rms-z.png  per-pixel fit RMS maps (mm)
//                                                with a colour bar (the paper's Fig. 5)
//   sigma-z.png                                  predicted depth sigma of the table (mm)
//   samples.png                                  board samples per pixel
//   plane-residuals.png                          per-pose plane-fit RMS and max (mm)
//   sv-offsets.png                               checkerboard sessions: per pose, the
//                                                stereo model's plane against the camera's
//   poses.csv                                    one row per pose

#include "fpp/calib/hybrid_calibrate.hpp"
#include "fpp/calib/report_folder.hpp"

#include <filesystem>
#include <string>

namespace fpp::calib {

// The Markdown summary.
std::string hybrid_summary_markdown(const HybridResult& result);

// Writes the report folder as a whole (an earlier report there is replaced).
// Throws IoError, or InputError if the folder exists and is not a report.
void write_hybrid_report(const std::filesystem::path& folder, const HybridResult& result);

} // namespace fpp::calib
