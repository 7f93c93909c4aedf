#pragma once
// The exposures of an HDR scan (board file `hdr`, fpp/scanner/board_config.hpp).
#include "fpp/drivers/camera.hpp"
#include "fpp/image.hpp"
#include "fpp/scanner/board_config.hpp"

#include <functional>
#include <vector>

namespace fpp::scanner {

// How a white preview frame exposes the scene.
struct PreviewExposure {
    std::size_t lit = 0;       // pixels at or above 2 % of full scale
    std::size_t saturated = 0; // pixels at or above 0.999 of full scale (the decoder's test)
    double saturated_fraction() const {
        return lit == 0 ? 0.0 : static_cast<double>(saturated) / static_cast<double>(lit);
    }
};
PreviewExposure measure_preview(const Frame& frame);

// Throws InputError(board file, "hdr.exposures_us[i]", ...) naming the
// camera's range for a fixed exposure the camera cannot set.
void check_hdr_exposures(const BoardConfig& board, drivers::ExposureRange range);

// hdr.auto: from `longest_us` down by factors of hdr.ratio (not below the
// camera's minimum), the first exposure whose white preview saturates at most
// hdr.max_saturated of the lit pixels; then shorter ones, each hdr.ratio
// times less, while the previous one saturates any pixel, at most hdr.passes
// in all. `preview(exposure_us)` takes a white frame at that exposure.
std::vector<double> automatic_exposures(const HdrConfig& hdr, double longest_us,
                                        drivers::ExposureRange range,
                                        const std::function<Frame(double)>& preview);

} // namespace fpp::scanner
