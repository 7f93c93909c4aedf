#pragma once
// Whether a decoded field fits the calibration as described or mirrored.
//
// A projector that shows its image mirrored (rear projection, ceiling mode)
// or a description with every shift reversed decodes to a field that is
// consistent with itself (no decode check can see it) but is the mirror
// image of the true one along x: p' = (W - 1) - p, pixel centres on
// integers. Triangulated with the calibration, it scatters in depth and
// misses the projector image. So the mirror image is triangulated too, and
// the field is called mirrored when the mirror image fits clearly better:
// more than 1 % of the decoded pixels fewer without a point, or its depth's
// 99th / 1st percentile ratio less than two thirds of the described one's
// with at most 0.5 % more pixels without a point. Measured: the virtual
// scanner's composite scene described mirrored, 39 % without a point and
// depth 154 .. 15919 mm against 0 % and 414 .. 540 mm; SLStudio's 2x3 skull
// with both shifts reversed, 3.6 % and 238 .. 1224 mm against 0.003 % and
// 368 .. 461 mm; every correct set here fits as described.

#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/decoder.hpp"
#include "fpp/point_cloud.hpp"

#include <optional>
#include <string>

namespace fpp::calib {

// Depth (Z, camera frame, mm) of a cloud's points: extremes and the 1st and
// 99th percentiles (0 without points).
struct CloudSummary {
    double z_min = 0, z_max = 0, z_p01 = 0, z_p99 = 0;
};
CloudSummary summarise(const PointCloud& cloud);

// How well a field fits: the share of decoded pixels without a point and
// the depth's 99th / 1st percentile ratio.
struct FieldFit {
    double no_point = 0; // fraction of the decoded pixels
    CloudSummary depth;
};
FieldFit field_fit(const SvStats& stats, const PointCloud& cloud);

// The reason, when `decoded` fits `calibration` clearly better mirrored
// along x than as `described` (reconstructed from it with `axes`); nullopt
// when it fits as described.
std::optional<std::string> mirrored_field(const StereoCalibration& calibration,
                                          const DecodeResult& decoded, ReconstructAxes axes,
                                          const FieldFit& described, int threads);

} // namespace fpp::calib
