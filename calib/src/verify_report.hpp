#pragma once
// What `fpp-calib verify` writes into its report folder (published whole,
// fpp/calib/report_folder.hpp):
//   verification.json   every figure, per position and sphere, the MPEs and
//                       verdicts (firmware/core/formats/verification-json.md)
//   summary.md          the same for people
//   sd.png              ball bar: SD per position with the MPE band
//   probing-form.png, probing-size.png   spheres: P_F, P_S per position and sphere
//   flatness.png        plate: F per position with the MPE band
//   residuals-N.png     position N: the fit residual per camera pixel

#include "fpp/calib/artefact.hpp"
#include "fpp/calib/verification.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace fpp::calib {

struct VerificationRecord {
    Artefact artefact;
    std::filesystem::path table;
    VerificationOptions options;
    std::vector<MeasuredPosition> positions;
    std::vector<FigureVerdict> figures;
};

// "pass", "fail" or "none" (no figure had an MPE).
std::string overall_verdict(const std::vector<FigureVerdict>& figures);

std::string verification_json(const VerificationRecord& record);
std::string verification_summary(const VerificationRecord& record);

// Writes the folder above atomically (an earlier report there is replaced).
void write_verification_report(const std::filesystem::path& folder,
                               const VerificationRecord& record);

} // namespace fpp::calib
