#include "fpp/scanner/exposure_plan.hpp"

#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include <algorithm>
#include <string>

namespace fpp::scanner {

namespace {

template <class T> PreviewExposure count(const Image<T>& image, double full) {
    const auto lit_level = static_cast<T>(0.02 * full);
    const auto saturated_level = static_cast<T>(0.999 * full);
    PreviewExposure e;
    const T* p = image.data();
    const std::size_t n = image.size().area();
    for (std::size_t i = 0; i < n; ++i) {
        e.lit += p[i] >= lit_level;
        e.saturated += p[i] >= saturated_level;
    }
    return e;
}

} // namespace

PreviewExposure measure_preview(const Frame& frame) {
    return frame.bit_depth == 8 ? count(frame.u8, 255.0) : count(frame.u16, 65535.0);
}

void check_hdr_exposures(const BoardConfig& board, drivers::ExposureRange range) {
    if (!board.hdr)
        return;
    const auto& list = board.hdr->exposures_us;
    for (std::size_t i = 0; i < list.size(); ++i)
        if (list[i] < range.min_us || list[i] > range.max_us)
            throw InputError(board.file, "hdr.exposures_us[" + std::to_string(i) + "]",
                             yaml_fields::format_real(list[i]) +
                                 " us is outside the camera's exposure range " +
                                 yaml_fields::format_real(range.min_us) + ".." +
                                 yaml_fields::format_real(range.max_us) + " us");
}

std::vector<double> automatic_exposures(const HdrConfig& hdr, double longest_us,
                                        drivers::ExposureRange range,
                                        const std::function<Frame(double)>& preview) {
    double exposure = std::clamp(longest_us, range.min_us, range.max_us);
    PreviewExposure seen = measure_preview(preview(exposure));
    while (seen.saturated_fraction() > hdr.max_saturated && exposure / hdr.ratio >= range.min_us) {
        exposure /= hdr.ratio;
        seen = measure_preview(preview(exposure));
    }
    std::vector<double> exposures{exposure};
    while (static_cast<int>(exposures.size()) < hdr.passes && seen.saturated > 0 &&
           exposure / hdr.ratio >= range.min_us) {
        exposure /= hdr.ratio;
        exposures.push_back(exposure);
        if (static_cast<int>(exposures.size()) < hdr.passes)
            seen = measure_preview(preview(exposure));
    }
    return exposures;
}

} // namespace fpp::scanner
