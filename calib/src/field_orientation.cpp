#include "field_orientation.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <vector>

namespace fpp::calib {

CloudSummary summarise(const PointCloud& cloud) {
    std::vector<float> z;
    z.reserve(cloud.xyz.pixel_count());
    const float* p = cloud.xyz.data();
    for (std::size_t i = 0; i < cloud.xyz.pixel_count(); ++i, p += 3)
        if (std::isfinite(p[2]))
            z.push_back(p[2]);
    CloudSummary s;
    if (z.empty())
        return s;
    auto at = [&](double q) {
        const std::size_t k =
            std::min(z.size() - 1, static_cast<std::size_t>(q * double(z.size())));
        std::nth_element(z.begin(), z.begin() + std::ptrdiff_t(k), z.end());
        return double(z[k]);
    };
    s.z_min = at(0.0);
    s.z_max = at(1.0);
    s.z_p01 = at(0.01);
    s.z_p99 = at(0.99);
    return s;
}

FieldFit field_fit(const SvStats& stats, const PointCloud& cloud) {
    FieldFit f;
    f.no_point =
        stats.decoded > 0 ? double(stats.decoded - stats.points) / double(stats.decoded) : 0.0;
    f.depth = summarise(cloud);
    return f;
}

namespace {

// 99th over 1st percentile of depth; infinite when the 1st is not in front.
double spread(const CloudSummary& d) {
    return d.z_p01 > 0 ? d.z_p99 / d.z_p01 : HUGE_VAL;
}

std::string describe(const FieldFit& f) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(2) << 100 * f.no_point
      << " % of the decoded pixels give no point, depth " << std::setprecision(0) << f.depth.z_p01
      << " .. " << f.depth.z_p99 << " mm (1st-99th percentile)";
    return s.str();
}

} // namespace

std::optional<std::string> mirrored_field(const StereoCalibration& calibration,
                                          const DecodeResult& decoded, ReconstructAxes axes,
                                          const FieldFit& described, int threads) {
    DecodeResult mirrored = decoded;
    const float last = static_cast<float>(calibration.projector_size.width - 1);
    for (std::size_t i = 0; i < mirrored.proj_x.pixel_count(); ++i)
        mirrored.proj_x.data()[i] = last - mirrored.proj_x.data()[i]; // NaN stays NaN
    SvOptions options;
    options.threads = threads;
    PointCloud cloud;
    const SvStats stats = SvReconstructor(calibration, options).reconstruct(mirrored, axes, cloud);
    const FieldFit fit = field_fit(stats, cloud);
    const bool fewer_misses = fit.no_point + 0.01 < described.no_point;
    const bool tighter = spread(fit.depth) * 1.5 < spread(described.depth) &&
                         fit.no_point <= described.no_point + 0.005;
    if (!fewer_misses && !tighter)
        return std::nullopt;
    return "the decoded field fits the calibration mirrored along x: as described, " +
           describe(described) + "; mirrored ((W - 1) - x), " + describe(fit) +
           ". A projector that shows its image mirrored (rear projection, ceiling mode) or a "
           "description with every shift reversed (shift_sign) gives this";
}

} // namespace fpp::calib
