#pragma once
// One position of a certified artefact measured from its capture with a
// coefficient table, as `fpp-calib verify` does it: the capture read and
// checked against the table (camera size, phase axis, the scanner's record
// of the table it used), decoded without smoothing, the table applied and
// the artefact measured (fpp/calib/verification.hpp). Shared by `verify`
// and `correct`, so that both measure the same clouds.

#include "fpp/calib/artefact.hpp"
#include "fpp/calib/verification.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/decoder.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace fpp::calib {

// FNV-1a of a file's bytes (IoError when it cannot be read), and as the
// 16 hex digits scan.json records.
std::uint64_t file_hash(const std::filesystem::path& path);
std::string hash_text(std::uint64_t hash);

struct CaptureMeasurement {
    std::filesystem::path table_path; // named in errors
    std::uint64_t table_hash = 0;     // 0: any table (no scan.json check)
    DecodeOptions decode;
};

// `table` is loaded from table_path on first use (and checked against each
// capture after). Throws InputError naming the capture (or its scan.json,
// or the table) for a capture the table does not fit; nothing when the
// decode failed (said on stderr).
std::optional<MeasuredPosition> measure_capture(const std::filesystem::path& capture,
                                                const CaptureMeasurement& how,
                                                const Artefact& artefact,
                                                std::optional<CoefficientTable>& table,
                                                const VerificationOptions& options);

// "position 2: length 150.0021 mm, SD +0.0021 mm; sphere 1 P_F ..."
std::string position_line(std::size_t k, const MeasuredPosition& p);

} // namespace fpp::calib
