#pragma once
// The files `fpp-calib decode` writes (a stable, documented interface):
//   proj_x.tiff, proj_y.tiff  float32, camera resolution, projector pixels, NaN invalid
//   modulation.tiff           float32, DN
//   mask.png                  8-bit, 255 where decoded, 0 elsewhere
//   flags.png                 8-bit, DecodeFlag bits per pixel (fpp/decoder.hpp)
//   proj_x.png, proj_y.png, modulation.png   false-colour previews
//   decode.md                 summary: lit pixels and the floor, coverage of the lit
//                             pixels, counts per reason a pixel was dropped
//                             (fpp/decode_report.hpp), the diagnosis of a suspect
//                             decode (fpp/decode_diagnosis.hpp), the consistency
//                             check (fpp/decode_consistency.hpp); with ground
//                             truth, the error against it

#include "fpp/calib/decode_options.hpp" // check_decode_options (the commands' options)
#include "fpp/capture_set.hpp"
#include "fpp/decode_consistency.hpp"
#include "fpp/decode_diagnosis.hpp"
#include "fpp/decode_report.hpp"
#include "fpp/decoder.hpp"

#include <filesystem>
#include <stdexcept>
#include <string>

namespace fpp::calib {

// Exit status of fpp-calib decode and reconstruct when the decode failed
// (DecodeDiagnosis::failed): the capture was read, but nearly nothing decoded
// or its description is evidently wrong. (2: bad input, 1: other errors.)
inline constexpr int kExitDecodeFailed = 3;
// Exit status when the decode is inconsistent with itself
// (fpp/decode_consistency.hpp): nearly every pixel "decoded", but the field
// shows a wrong description (the field to check is named). Overridden by
// --accept-inconsistent.
inline constexpr int kExitInconsistent = 5;

// A decode refused by a check, with the exit status to end with and the
// reason (main prints it).
class DecodeRefused : public std::runtime_error {
public:
    DecodeRefused(int exit_code, const std::string& why)
        : std::runtime_error(why), exit_code_(exit_code) {}
    int exit_code() const { return exit_code_; }

private:
    int exit_code_;
};

// The consistency check's figures for decode.md ("## Consistency").
std::string consistency_text(const DecodeConsistency& consistency);

// Writes the images above (each atomically) into `folder` (created if needed).
void write_decode_images(const std::filesystem::path& folder, const DecodeResult& result,
                         const CaptureManifest& manifest);

// Markdown summary of a decode, with its statistics and diagnosis; compares
// with the capture's truth when it has one (capture.folder locates the truth files).
std::string decode_summary(const DecodeResult& result, const CaptureSet& capture,
                           const DecodeStatistics& stats, const DecodeDiagnosis& diagnosis,
                           double decode_seconds);

// Same, computing the statistics and the diagnosis (with default
// DecodeOptions) itself.
std::string decode_summary(const DecodeResult& result, const CaptureSet& capture,
                           double decode_seconds);

// The "## Pixels" section alone: lit pixels and the floor, coverage of the
// lit pixels, and the count of each reason a pixel was dropped (Markdown).
std::string decode_statistics_text(const DecodeStatistics& stats);

} // namespace fpp::calib
