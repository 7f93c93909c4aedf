#pragma once
// What `fpp-calib correct --report DIR` writes (published whole,
// fpp/calib/report_folder.hpp):
//   summary.md                    the correction round by round, where the
//                                 new trueness comes from, and the held-out
//                                 positions before and after
//   before/verification.json      the held-out positions with the old table
//   after/verification.json       ... and with the corrected one
//                                 (firmware/core/formats/verification-json.md)

#include "verify_report.hpp"

#include "fpp/calib/depth_scale.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace fpp::calib {

struct CorrectionRound {
    double camera_focal_scale = 1; // the calibration measured in this round
    DepthScaleFit fit;             // what the used positions showed with its table
};

struct CorrectionRecord {
    std::filesystem::path artefact, calibration, session, table, out_calibration, out_table;
    std::vector<std::filesystem::path> used;
    std::vector<CorrectionRound> rounds; // round 0: the input calibration
    bool converged = false;              // the last round's correction within its noise
    double final_focal_scale = 1;
    Trueness predicted;                              // the input calibration's
    Trueness corrected;                              // written with the corrected calibration
    std::optional<VerificationRecord> before, after; // the held-out positions
};

std::string correction_summary(const CorrectionRecord& record);

// Writes the folder above atomically (an earlier report there is replaced).
void write_correction_report(const std::filesystem::path& folder, const CorrectionRecord& record);

} // namespace fpp::calib
