#include "fpp/coordinate_filter.hpp"

#include "fpp/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace fpp {

void CoordinateFilterOptions::validate() const {
    auto fail = [](const std::string& field, const std::string& what) {
        throw std::invalid_argument("CoordinateFilterOptions." + field + ": " + what);
    };
    if (radius < 0 || radius > kMaxRadius)
        fail("radius",
             "must be 0.." + std::to_string(kMaxRadius) + ", got " + std::to_string(radius));
    if (!std::isfinite(tolerance_px) || tolerance_px < 0)
        fail("tolerance_px", "must be 0 (automatic) or a positive number of projector pixels");
    if (!std::isfinite(tolerance_sigmas) || !(tolerance_sigmas > 0))
        fail("tolerance_sigmas", "must be a positive number");
    if (!std::isfinite(sigma_px) || sigma_px < 0)
        fail("sigma_px", "must be 0 (uniform) or a positive number of camera pixels");
    if (threads < 0)
        fail("threads", "must be 0 (all cores) or positive");
}

namespace {

// Added to the offsets' variances (camera px^2; a full 5 x 5 window has
// 2): keeps the plane fit well posed when the accepted neighbours lie on a
// line, at a negligible pull of the slope correction toward 0 otherwise.
constexpr float kRidge = 1e-3f;

// Median of values[0, n) (the upper one for even n); reorders them.
float median_in_place(float* values, int n) {
    float* mid = values + n / 2;
    std::nth_element(values, mid, values + n);
    return *mid;
}

// The filter for rows [row_begin, row_end). `differences` holds room for
// every adjacent pair of one window; `weights` the (2r+1)^2 offset weights.
void smooth_rows(const Image<float>& in, Image<float>& out, int radius, float tolerance,
                 const float* weights, float* differences, int row_begin, int row_end) {
    const int w = in.width(), h = in.height();
    const int side = 2 * radius + 1;
    for (int y = row_begin; y < row_end; ++y) {
        const float* src_row = in.row(y);
        float* dst_row = out.row(y);
        const int y0 = std::max(0, y - radius), y1 = std::min(h - 1, y + radius);
        for (int x = 0; x < w; ++x) {
            const float v = src_row[x];
            if (!std::isfinite(v)) {
                dst_row[x] = v;
                continue;
            }
            const int x0 = std::max(0, x - radius), x1 = std::min(w - 1, x + radius);

            // 1. Robust local gradient, projector px per camera px. A NaN on
            // either side makes the difference NaN, which is skipped.
            int nx = 0, ny = 0;
            for (int yy = y0; yy <= y1; ++yy) {
                const float* r = in.row(yy);
                for (int xx = x0; xx < x1; ++xx) {
                    const float d = r[xx + 1] - r[xx];
                    if (std::isfinite(d))
                        differences[nx++] = d;
                }
            }
            const float gx = nx > 0 ? median_in_place(differences, nx) : 0.0f;
            for (int yy = y0; yy < y1; ++yy) {
                const float* r0 = in.row(yy);
                const float* r1 = in.row(yy + 1);
                for (int xx = x0; xx <= x1; ++xx) {
                    const float d = r1[xx] - r0[xx];
                    if (std::isfinite(d))
                        differences[ny++] = d;
                }
            }
            const float gy = ny > 0 ? median_in_place(differences, ny) : 0.0f;

            // 2. The neighbours that follow the local plane through v within
            // the tolerance (NaN neighbours fail the comparison and drop
            // out), with the weighted moments of their offsets and
            // deviations from that plane.
            float s_w = 0, s_x = 0, s_y = 0, s_xx = 0, s_xy = 0, s_yy = 0;
            float s_e = 0, s_xe = 0, s_ye = 0;
            for (int yy = y0; yy <= y1; ++yy) {
                const float* r = in.row(yy);
                const float dy = static_cast<float>(yy - y);
                const float* wrow =
                    weights + std::size_t(yy - y + radius) * std::size_t(side) + radius;
                const float base = v + gy * dy;
                for (int xx = x0; xx <= x1; ++xx) {
                    const float dx = static_cast<float>(xx - x);
                    const float e = r[xx] - (base + gx * dx);
                    if (!(std::fabs(e) <= tolerance))
                        continue;
                    const float wt = wrow[xx - x];
                    s_w += wt;
                    s_x += wt * dx;
                    s_y += wt * dy;
                    s_xx += wt * dx * dx;
                    s_xy += wt * dx * dy;
                    s_yy += wt * dy * dy;
                    s_e += wt * e;
                    s_xe += wt * dx * e;
                    s_ye += wt * dy * e;
                }
            }
            // 3. Weighted least-squares plane e = c + a dx + b dy through the
            // accepted deviations, evaluated at the centre (c). For a full,
            // symmetric window this is their mean; beside an edge or the
            // image border it does not tilt toward the side that has more
            // neighbours. The slope corrections (a, b) are ridge-regularised
            // so that a line of neighbours (no spread in one direction) is
            // still well posed. The centre is always accepted, so s_w > 0.
            const float mx = s_x / s_w, my = s_y / s_w, me = s_e / s_w;
            const float cxx = s_xx / s_w - mx * mx + kRidge, cyy = s_yy / s_w - my * my + kRidge;
            const float cxy = s_xy / s_w - mx * my;
            const float cxe = s_xe / s_w - mx * me, cye = s_ye / s_w - my * me;
            const float det = cxx * cyy - cxy * cxy;
            const float a = (cyy * cxe - cxy * cye) / det;
            const float b = (cxx * cye - cxy * cxe) / det;
            const float c = me - a * mx - b * my;
            // Extrapolating a plane can overshoot; a pixel never moves by
            // more than the tolerance.
            dst_row[x] = v + std::clamp(c, -tolerance, tolerance);
        }
    }
}

} // namespace

double estimate_coordinate_noise(const Image<float>& coordinates) {
    if (coordinates.channels() != 1)
        throw std::invalid_argument(
            "estimate_coordinate_noise: expected a 1-channel coordinate image");
    const int w = coordinates.width(), h = coordinates.height();
    std::vector<float> second;
    second.reserve(2 * coordinates.pixel_count());
    for (int y = 0; y < h; ++y) {
        const float* r = coordinates.row(y);
        for (int x = 1; x + 1 < w; ++x) {
            const float d = r[x - 1] - 2.0f * r[x] + r[x + 1];
            if (std::isfinite(d))
                second.push_back(std::fabs(d));
        }
    }
    for (int y = 1; y + 1 < h; ++y) {
        const float* r0 = coordinates.row(y - 1);
        const float* r1 = coordinates.row(y);
        const float* r2 = coordinates.row(y + 1);
        for (int x = 0; x < w; ++x) {
            const float d = r0[x] - 2.0f * r1[x] + r2[x];
            if (std::isfinite(d))
                second.push_back(std::fabs(d));
        }
    }
    if (second.size() < 16)
        return 0.0;
    const double median = double(median_in_place(second.data(), static_cast<int>(second.size())));
    return 1.4826 * median / std::sqrt(6.0);
}

double resolve_tolerance(const Image<float>& coordinates, const CoordinateFilterOptions& options) {
    options.validate();
    if (options.tolerance_px > 0)
        return options.tolerance_px;
    return std::max(CoordinateFilterOptions::kMinTolerance,
                    options.tolerance_sigmas * estimate_coordinate_noise(coordinates));
}

double smooth_coordinates(const Image<float>& in, Image<float>& out,
                          const CoordinateFilterOptions& options, ThreadPool* pool) {
    options.validate();
    if (in.channels() != 1)
        throw std::invalid_argument("smooth_coordinates: expected a 1-channel coordinate image");
    if (&in == &out)
        throw std::invalid_argument("smooth_coordinates: output must not be the input");
    if (out.size() != in.size() || out.channels() != 1)
        out = Image<float>(in.size(), 1);
    const int r = options.radius;
    if (in.empty() || r == 0) {
        std::copy(in.storage().begin(), in.storage().end(), out.storage().begin());
        return r == 0 ? 0.0 : resolve_tolerance(in, options);
    }
    const double tolerance = resolve_tolerance(in, options);
    const int side = 2 * r + 1;
    std::vector<float> weights(std::size_t(side) * std::size_t(side), 1.0f);
    if (options.sigma_px > 0) {
        const double k = -0.5 / (options.sigma_px * options.sigma_px);
        for (int dy = -r; dy <= r; ++dy)
            for (int dx = -r; dx <= r; ++dx)
                weights[std::size_t(dy + r) * std::size_t(side) + std::size_t(dx + r)] =
                    static_cast<float>(std::exp(k * double(dx * dx + dy * dy)));
    }
    ThreadPool& workers = pool ? *pool : ThreadPool::shared(options.threads);
    // Room for the adjacent pairs of one window along either axis.
    const std::size_t pairs = std::size_t(side) * std::size_t(side - 1);
    std::vector<float> scratch(pairs * std::size_t(workers.size()));
    // Rows in chunks of 8: enough chunks to balance the workers.
    workers.parallel_for(in.height(), 8, [&](int begin, int end, int worker) {
        smooth_rows(in, out, r, static_cast<float>(tolerance), weights.data(),
                    scratch.data() + pairs * std::size_t(worker), begin, end);
    });
    return tolerance;
}

CoordinateFilterReport smooth_coordinates(DecodeResult& decoded,
                                          const CoordinateFilterOptions& options,
                                          Image<float>& scratch, ThreadPool* pool) {
    options.validate();
    CoordinateFilterReport report;
    if (options.radius == 0)
        return report;
    for (Image<float>* axis : {&decoded.proj_x, &decoded.proj_y}) {
        if (axis->empty())
            continue;
        const double tolerance = smooth_coordinates(*axis, scratch, options, pool);
        (axis == &decoded.proj_x ? report.tolerance_x : report.tolerance_y) = tolerance;
        std::swap(*axis, scratch);
    }
    return report;
}

} // namespace fpp
