#pragma once
// A capture set decoded and a coefficient table applied to it: the one code
// path of `fpp-calib reconstruct --table` and `fpp-calib verify`, so that
// verify measures exactly the clouds reconstruct writes.

#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/coordinate_filter.hpp"
#include "fpp/decode_report.hpp"
#include "fpp/decoder.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/table_kernel.hpp"

#include <filesystem>
#include <optional>

namespace fpp::calib {

// The capture codes the projector column, and the row when `requested` is xy
// (InputError naming capture.yaml's `sequence` otherwise).
void check_capture_axes(const CaptureSet& capture, ReconstructAxes requested);

// The table fits the capture: camera size (naming the capture's
// capture.yaml), phase axis x and projector size (naming the table).
void check_table_fits_capture(const CoefficientTable& table,
                              const std::filesystem::path& table_path, const CaptureSet& capture);

// The table read, validated whole (header, every tile's CRC) and checked
// against the capture as above.
CoefficientTable load_table_for_capture(const std::filesystem::path& table_path,
                                        const CaptureSet& capture);

// A capture decoded, its projector coordinates smoothed (a radius of 0 leaves
// them as decoded).
struct DecodedScan {
    DecodeResult decoded;
    DecodeStatistics decode_stats;
    CoordinateFilterReport smoothing;
    double decode_seconds = 0, smooth_seconds = 0;
};

// Nothing when the decode failed (fpp/decode_diagnosis.hpp): the likely cause
// is then said on stderr, naming the capture's folder. A decode inconsistent
// with itself (fpp/decode_consistency.hpp) throws DecodeRefused
// (kExitInconsistent, naming the field to check), unless `accept_inconsistent`
// (then a warning).
std::optional<DecodedScan> decode_and_smooth(const CaptureSet& capture, const DecodeOptions& decode,
                                             const CoordinateFilterOptions& smooth,
                                             bool accept_inconsistent = false);

// The table applied to the decoded projector column (tiles over `threads`
// workers, 0 = all cores); the cloud's quality and intensity are the
// decode's modulation and mean.
struct TableCloud {
    PointCloud cloud;
    TableApplyStats stats;
    double seconds = 0;
};
TableCloud apply_table_to_scan(const CoefficientTable& table, const DecodeResult& decoded,
                               int threads);

} // namespace fpp::calib
