#pragma once
// A cloud's depth error against a simulated scene's truth: per camera pixel,
// Z(point) - Z(true) along the pixel's ray (camera frame, mm), over pixels
// where both have a point, with nothing removed; and beside it the error less
// its mean, and the RMS residual of a least-squares plane through the
// cloud's points (a plane scene's flatness).
// Header-only: it needs fpp_calib_lib (fit_plane), which the support library
// does not link.
#include "fpp/calib/shape_fit.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp" // Vec3

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace fpp::test {

struct DepthError {
    double rms = 0, mean = 0;
    double shape = 0;    // RMS about the mean (the error once the offset is removed)
    double flatness = 0; // RMS residual of a least-squares plane through the points
    std::size_t n = 0;   // pixels compared
};

// `xyz` and `truth`: 3-channel float images of X, Y, Z per camera pixel (NaN
// where there is no point).
inline DepthError depth_error(const Image<float>& xyz, const Image<float>& truth) {
    DepthError e;
    double sum = 0, sum2 = 0;
    std::vector<Vec3> points;
    for (std::size_t i = 0; i < truth.pixel_count(); ++i) {
        const double z = double(xyz.data()[3 * i + 2]), zt = double(truth.data()[3 * i + 2]);
        if (std::isfinite(z))
            points.push_back({double(xyz.data()[3 * i]), double(xyz.data()[3 * i + 1]), z});
        if (!std::isfinite(z) || !std::isfinite(zt))
            continue;
        sum += z - zt;
        sum2 += (z - zt) * (z - zt);
        ++e.n;
    }
    if (e.n) {
        e.mean = sum / double(e.n);
        e.rms = std::sqrt(sum2 / double(e.n));
        e.shape = std::sqrt(std::max(0.0, e.rms * e.rms - e.mean * e.mean));
    }
    if (points.size() > 3)
        e.flatness = calib::fit_plane(points).fit.rms;
    return e;
}

} // namespace fpp::test
