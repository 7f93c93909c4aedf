// Two-camera scanning: matching along rectified rows and triangulation
// (fpp/calib/two_camera.hpp states the rules).

#include "fpp/calib/two_camera.hpp"

#include "fpp/parallel.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace fpp::calib {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

// Bilinear sample at (px, py) (inside the image) between four finite
// neighbours within `max_step` of each other; NaN otherwise (a gap or a
// depth edge is never interpolated across).
float guarded_bilinear(const Image<float>& image, float px, float py, float max_step) {
    const int w = image.width(), h = image.height();
    const int x0 = std::min(static_cast<int>(std::floor(px)), w - 2);
    const int y0 = std::min(static_cast<int>(std::floor(py)), h - 2);
    if (x0 < 0 || y0 < 0)
        return kNaN;
    const float* r0 = image.row(y0) + x0;
    const float* r1 = image.row(y0 + 1) + x0;
    const float a = r0[0], b = r0[1], c = r1[0], d = r1[1];
    const float lo = std::min(std::min(a, b), std::min(c, d));
    const float hi = std::max(std::max(a, b), std::max(c, d));
    if (!(hi - lo <= max_step)) // false for any NaN too
        return kNaN;
    const float fx = px - float(x0), fy = py - float(y0);
    return (a + (b - a) * fx) * (1 - fy) + (c + (d - c) * fx) * fy;
}

// Camera 2's decoded map resampled onto the rectified grid.
Image<float> rectify_map(const Image<float>& decoded, const Image<float>& source, float max_step,
                         ThreadPool& pool) {
    Image<float> out(source.size(), 1, kNaN);
    pool.parallel_for(source.height(), 8, [&](int begin, int end, int) {
        for (int j = begin; j < end; ++j) {
            const float* s = source.row(j);
            float* o = out.row(j);
            for (int i = 0; i < source.width(); ++i, s += 2)
                if (std::isfinite(s[0]))
                    o[i] = guarded_bilinear(decoded, s[0], s[1], max_step);
        }
    });
    return out;
}

// A run of rectified cells [begin, end] (end > begin) on one row along which
// u moves strictly in the image's direction by at most max_step per cell.
struct Run {
    int begin, end;
};

struct RowRuns {
    std::vector<Run> runs;
    std::vector<std::size_t> row_start; // runs of row j: [row_start[j], row_start[j + 1])
};

bool good_step(float a, float b, float sign, float max_step) {
    const float step = sign * (b - a);
    return step > 0 && step <= max_step; // false for NaN
}

// +1 if u rises with the rectified column in most of camera 2's image, else -1.
float rising_sign(const Image<float>& u, float max_step) {
    long long rising = 0, falling = 0;
    for (int j = 0; j < u.height(); ++j) {
        const float* r = u.row(j);
        for (int i = 0; i + 1 < u.width(); ++i) {
            rising += good_step(r[i], r[i + 1], 1.0f, max_step);
            falling += good_step(r[i], r[i + 1], -1.0f, max_step);
        }
    }
    return rising >= falling ? 1.0f : -1.0f;
}

RowRuns find_runs(const Image<float>& u, float sign, float max_step) {
    RowRuns out;
    out.row_start.reserve(std::size_t(u.height()) + 1);
    for (int j = 0; j < u.height(); ++j) {
        out.row_start.push_back(out.runs.size());
        const float* r = u.row(j);
        int i = 0;
        while (i + 1 < u.width()) {
            if (!good_step(r[i], r[i + 1], sign, max_step)) {
                ++i;
                continue;
            }
            const int begin = i;
            while (i + 1 < u.width() && good_step(r[i], r[i + 1], sign, max_step))
                ++i;
            out.runs.push_back({begin, i});
        }
    }
    out.row_start.push_back(out.runs.size());
    return out;
}

enum class RowMatch { found, none, ambiguous, v_disagree };

struct Matcher {
    const Image<float>& u2;
    const Image<float>* v2; // null when y is not used
    const RowRuns& runs;
    float sign;
    TwoCameraOptions options;

    // Sub-pixel column on rectified row `j` where u2 = u1 (rules in the header).
    // `v_at`: v2 at the match, when v is used.
    RowMatch match(int j, float u1, float v1, double& column, double& v_at) const {
        constexpr int kMaxCandidates = 8;
        std::array<double, kMaxCandidates> found{};
        int count = 0;
        bool overflow = false;
        const float* r = u2.row(j);
        const float target = sign * u1;
        for (std::size_t k = runs.row_start[std::size_t(j)]; k < runs.row_start[std::size_t(j) + 1];
             ++k) {
            const Run run = runs.runs[k];
            if (!(sign * r[run.begin] <= target && target <= sign * r[run.end]))
                continue;
            // Last cell of the run with sign*u <= target (binary search).
            int lo = run.begin, hi = run.end;
            while (hi - lo > 1) {
                const int mid = (lo + hi) / 2;
                (sign * r[mid] <= target ? lo : hi) = mid;
            }
            const double x = lo + double(u1 - r[lo]) / double(r[hi] - r[lo]);
            if (count < kMaxCandidates)
                found[std::size_t(count++)] = x;
            else
                overflow = true;
        }
        if (count == 0)
            return RowMatch::none;
        if (v2 && std::isfinite(v1)) {
            // The candidate nearest in v; the caller checks v at y1 itself
            // (v changes between the row and y1).
            double best = std::numeric_limits<double>::infinity();
            bool any = false;
            for (int c = 0; c < count; ++c) {
                const double x = found[std::size_t(c)];
                const int i = std::min(static_cast<int>(x), u2.width() - 2);
                const float* v = v2->row(j) + i;
                const double v_here = double(v[0]) + double(v[1] - v[0]) * (x - i);
                const double miss = std::abs(v_here - double(v1));
                if (miss < best) { // false for NaN
                    best = miss;
                    column = x;
                    v_at = v_here;
                    any = true;
                }
            }
            return any ? RowMatch::found : RowMatch::v_disagree;
        }
        const auto [lo, hi] = std::minmax_element(found.begin(), found.begin() + count);
        if (overflow || *hi - *lo > options.cluster_px)
            return RowMatch::ambiguous;
        double sum = 0;
        for (int c = 0; c < count; ++c)
            sum += found[std::size_t(c)];
        column = sum / count;
        return RowMatch::found;
    }
};

void add(TwoCameraStats& total, const TwoCameraStats& s) {
    total.first_valid += s.first_valid;
    total.points += s.points;
    total.outside += s.outside;
    total.no_match += s.no_match;
    total.ambiguous += s.ambiguous;
    total.v_disagree += s.v_disagree;
    total.row_mismatch += s.row_mismatch;
    total.behind += s.behind;
    total.occluded += s.occluded;
}

void count_failure(TwoCameraStats& s, RowMatch m) {
    if (m == RowMatch::ambiguous)
        ++s.ambiguous;
    else if (m == RowMatch::v_disagree)
        ++s.v_disagree;
    else
        ++s.no_match;
}

} // namespace

TwoCameraStats TwoCameraReconstructor::reconstruct(const DecodeResult& first,
                                                   const DecodeResult& second,
                                                   PointCloud& cloud) const {
    if (first.proj_x.empty() || second.proj_x.empty())
        throw std::invalid_argument("two-camera scanning needs the projector column (x) decoded "
                                    "in both cameras");
    if (first.proj_x.size() != pair_.first_size || second.proj_x.size() != pair_.second_size)
        throw std::invalid_argument("the decoded images' sizes differ from the calibration's");
    const bool use_v = !first.proj_y.empty() && !second.proj_y.empty();
    const float max_step = static_cast<float>(options_.max_step_px);
    ThreadPool& pool = ThreadPool::shared(options_.threads);

    const Image<float> u2 = rectify_map(second.proj_x, second_source_, max_step, pool);
    const Image<float> v2 =
        use_v ? rectify_map(second.proj_y, second_source_, max_step, pool) : Image<float>();
    const float sign = rising_sign(u2, max_step);
    const RowRuns runs = find_runs(u2, sign, max_step);
    const Matcher matcher{u2, use_v ? &v2 : nullptr, runs, sign, options_};

    const Size size = pair_.first_size;
    cloud = PointCloud{};
    cloud.xyz = Image<float>(size, 3, kNaN);
    cloud.quality = first.modulation;
    cloud.intensity = first.mean;
    std::vector<TwoCameraStats> per_worker(std::size_t(pool.size()));
    const TwoCameraRectification& r = rect_;
    // Pass 1: the rectified disparity x1 - x' of every camera-1 pixel (NaN: none).
    Image<float> disparity(size, 1, kNaN);
    pool.parallel_for(size.height, 4, [&](int begin, int end, int worker) {
        TwoCameraStats& s = per_worker[std::size_t(worker)];
        for (int y = begin; y < end; ++y) {
            const float* u = first.proj_x.row(y);
            const float* v = use_v ? first.proj_y.row(y) : nullptr;
            const float* rect = first_rectified_.row(y);
            float* out = disparity.row(y);
            for (int x = 0; x < size.width; ++x) {
                const float u1 = u[x];
                if (!std::isfinite(u1))
                    continue;
                ++s.first_valid;
                const float x1 = rect[2 * x], y1 = rect[2 * x + 1];
                if (!(y1 >= 0 && y1 < float(r.grid.height - 1))) { // false for NaN
                    ++s.outside;
                    continue;
                }
                const int row = static_cast<int>(y1);
                const float v1 = v ? v[x] : kNaN;
                double xa = 0, xb = 0, va = kNoValue, vb = kNoValue;
                const RowMatch a = matcher.match(row, u1, v1, xa, va);
                const RowMatch b =
                    a == RowMatch::found ? matcher.match(row + 1, u1, v1, xb, vb) : a;
                if (a != RowMatch::found || b != RowMatch::found) {
                    count_failure(s, a != RowMatch::found ? a : b);
                    continue;
                }
                if (std::abs(xa - xb) > options_.max_row_step_px) {
                    ++s.row_mismatch;
                    continue;
                }
                const double t = double(y1) - row;
                if (std::isfinite(va) &&
                    !(std::abs(va + (vb - va) * t - double(v1)) <= options_.max_v_px)) {
                    ++s.v_disagree;
                    continue;
                }
                const double d = double(x1) - (xa + (xb - xa) * t);
                if (!(d * r.baseline > 0)) {
                    ++s.behind;
                    continue;
                }
                out[x] = static_cast<float>(d);
            }
        }
    });
    // Pass 2: per rectified cell of camera 2, the largest |disparity| matched
    // to it (the surface camera 2 sees there: the nearest along its ray).
    Image<float> nearest(r.grid, 1, 0.0f);
    auto cells = [&](int x, int y, auto&& visit) {
        const float* rect = first_rectified_.row(y) + 2 * x;
        const float d = disparity.row(y)[x];
        const int row = static_cast<int>(rect[1]);
        const int column = static_cast<int>(std::floor(rect[0] - d));
        for (int j = row; j <= row + 1; ++j)
            for (int i = std::max(column, 0); i <= std::min(column + 1, r.grid.width - 1); ++i)
                visit(nearest.row(j)[i]);
    };
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x)
            if (const float d = std::abs(disparity.row(y)[x]); std::isfinite(d))
                cells(x, y, [d](float& cell) { cell = std::max(cell, d); });
    // Pass 3: drop pixels hidden from camera 2 (a nearer matched surface owns
    // their cells: the u they matched was that surface's), triangulate the rest.
    const Mat3 R1t = transpose(r.R1);
    const float margin = static_cast<float>(options_.occlusion_margin_px);
    pool.parallel_for(size.height, 4, [&](int begin, int end, int worker) {
        TwoCameraStats& s = per_worker[std::size_t(worker)];
        for (int y = begin; y < end; ++y) {
            const float* rect = first_rectified_.row(y);
            float* out = cloud.xyz.row(y);
            for (int x = 0; x < size.width; ++x) {
                const float d = disparity.row(y)[x];
                if (!std::isfinite(d))
                    continue;
                float occluder = 0;
                cells(x, y, [&occluder](float& cell) { occluder = std::max(occluder, cell); });
                if (occluder > std::abs(d) + margin) {
                    ++s.occluded;
                    continue;
                }
                const double x1 = rect[2 * x], y1 = rect[2 * x + 1];
                const double z = r.f * r.baseline / double(d);
                const Vec3 p = mul(R1t, Vec3{(x1 - r.cx) * z / r.f, (y1 - r.cy) * z / r.f, z});
                out[3 * x] = static_cast<float>(p[0]);
                out[3 * x + 1] = static_cast<float>(p[1]);
                out[3 * x + 2] = static_cast<float>(p[2]);
                ++s.points;
            }
        }
    });
    TwoCameraStats total;
    for (const TwoCameraStats& s : per_worker)
        add(total, s);
    for (const float value : second.proj_x.storage())
        total.second_valid += std::isfinite(value) ? 1 : 0;
    return total;
}

} // namespace fpp::calib
