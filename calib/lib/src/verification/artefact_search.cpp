// Finding an artefact's spheres among other surfaces (see the header; the
// plate: plate_search.cpp).

#include "fpp/calib/artefact_search.hpp"

#include "organised_points.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <unordered_map>

namespace fpp::calib {

namespace {

using namespace organised;

constexpr double kPi = 3.14159265358979323846;
// Cells across the coverage grid (hemisphere_coverage): 156 of them on
// the hemisphere, about 9 mm^2 each on a 30 mm sphere.
constexpr int kCoverageGrid = 14;

// The median angle between horizontally adjacent points' rays (radians): a
// pixel's footprint at depth z is about this times z.
double pixel_angle(const Image<float>& xyz) {
    std::vector<double> steps;
    const int w = xyz.width(), h = xyz.height();
    const int row_step = std::max(1, h / 64);
    for (int y = 0; y < h; y += row_step)
        for (int x = 0; x + 1 < w; ++x) {
            const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
            if (!finite_at(xyz, i) || !finite_at(xyz, i + 1))
                continue;
            const Vector3d a = point_at(xyz, i), b = point_at(xyz, i + 1);
            if (a.z() > 0 && b.z() > 0)
                steps.push_back(
                    std::hypot(a.x() / a.z() - b.x() / b.z(), a.y() / a.z() - b.y() / b.z()));
        }
    if (steps.empty())
        return 0;
    std::nth_element(steps.begin(), steps.begin() + std::ptrdiff_t(steps.size() / 2), steps.end());
    return steps[steps.size() / 2];
}

// Separable square dilation of a 0/1 mask by `r` pixels.
void dilate(std::vector<std::uint8_t>& mask, int w, int h, int r) {
    if (r <= 0)
        return;
    std::vector<std::uint8_t> tmp(mask.size(), 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::uint8_t v = 0;
            for (int k = std::max(0, x - r); k <= std::min(w - 1, x + r) && !v; ++k)
                v = mask[std::size_t(y) * std::size_t(w) + std::size_t(k)];
            tmp[std::size_t(y) * std::size_t(w) + std::size_t(x)] = v;
        }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::uint8_t v = 0;
            for (int k = std::max(0, y - r); k <= std::min(h - 1, y + r) && !v; ++k)
                v = tmp[std::size_t(k) * std::size_t(w) + std::size_t(x)];
            mask[std::size_t(y) * std::size_t(w) + std::size_t(x)] = v;
        }
}

// Usable points whose distance from `centre` is within `band` of `radius`.
void gather_shell(const Image<float>& xyz, std::span<const std::uint8_t> usable,
                  const Vector3d& centre, double radius, double band,
                  std::vector<std::uint32_t>& pixels, std::vector<Vec3>& points) {
    pixels.clear();
    points.clear();
    for (std::size_t i = 0; i < usable.size(); ++i) {
        if (!usable[i])
            continue;
        const Vector3d p = point_at(xyz, i);
        if (std::abs((p - centre).norm() - radius) < band) {
            pixels.push_back(static_cast<std::uint32_t>(i));
            points.push_back(to_vec(p));
        }
    }
}

// Vote cells: integer coordinates packed into one key.
constexpr std::int64_t kCellRange = std::int64_t{1} << 20;
std::int64_t cell_key(std::int64_t x, std::int64_t y, std::int64_t z) {
    return ((x + kCellRange) << 42) | ((y + kCellRange) << 21) | (z + kCellRange);
}

struct Votes {
    std::vector<Vector3d> centres; // one candidate centre per voting point
    std::unordered_map<std::int64_t, std::uint32_t> cells;
    double cell = 1;
    std::int64_t index(double v) const { return static_cast<std::int64_t>(std::floor(v / cell)); }
    std::uint32_t count(std::int64_t x, std::int64_t y, std::int64_t z) const {
        const auto it = cells.find(cell_key(x, y, z));
        return it == cells.end() ? 0 : it->second;
    }
};

// The centre of a sphere of `radius` through each usable point: p - r n, n
// its normal from the points about r/4 either side (the normal's noise is
// the points' noise over that baseline), towards the camera; NaN where the
// neighbours are not all usable. `steps` gets the neighbour distance in pixels.
std::vector<Vector3d> candidate_centres(const Image<float>& xyz,
                                        std::span<const std::uint8_t> usable, double radius,
                                        std::vector<int>& steps) {
    const double angle = pixel_angle(xyz);
    const int w = xyz.width(), h = xyz.height();
    std::vector<Vector3d> centres(xyz.pixel_count(),
                                  Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
    steps.assign(xyz.pixel_count(), 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
            if (!usable[i])
                continue;
            const Vector3d p = point_at(xyz, i);
            const int s = std::clamp(
                angle > 0 ? static_cast<int>(std::lround(radius / 4 / (angle * p.z()))) : 1, 1, 16);
            if (x < s || y < s || x + s >= w || y + s >= h)
                continue;
            const std::size_t l = i - std::size_t(s), r = i + std::size_t(s);
            const std::size_t u = i - std::size_t(s) * std::size_t(w),
                              d = i + std::size_t(s) * std::size_t(w);
            if (!usable[l] || !usable[r] || !usable[u] || !usable[d])
                continue;
            Vector3d n =
                (point_at(xyz, r) - point_at(xyz, l)).cross(point_at(xyz, d) - point_at(xyz, u));
            if (!(n.norm() > 0))
                continue;
            n.normalize();
            if (n.dot(p) > 0)
                n = -n; // towards the camera
            centres[i] = p - radius * n;
            steps[i] = s;
        }
    return centres;
}

// Votes of the points whose candidate centre the points r/4 either side
// that have one agree with (within 0.15 r; at least one of them): on a
// sphere of the radius they all name its centre, while on a plane or a bar
// they stand a chord apart, so that flat and singly curved surfaces cast no
// vote.
Votes vote_centres(const Image<float>& xyz, std::span<const std::uint8_t> usable, double radius) {
    Votes v;
    v.cell = std::max(0.5, radius / 5);
    std::vector<int> steps;
    const std::vector<Vector3d> centres = candidate_centres(xyz, usable, radius, steps);
    const int w = xyz.width(), h = xyz.height();
    const double limit = 0.9 * double(kCellRange) * v.cell;
    const double agree = 0.15 * radius;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
            const int s = steps[i];
            if (s == 0)
                continue;
            const Vector3d& c = centres[i];
            int agreeing = 0, disagreeing = 0;
            const std::size_t neighbours[4] = {i - std::size_t(s), i + std::size_t(s),
                                               i - std::size_t(s) * std::size_t(w),
                                               i + std::size_t(s) * std::size_t(w)};
            for (const std::size_t j : neighbours)
                if (steps[j] > 0)
                    ++((centres[j] - c).norm() < agree ? agreeing : disagreeing);
            if (agreeing == 0 || disagreeing > 0)
                continue;
            if (std::abs(c.x()) > limit || std::abs(c.y()) > limit || std::abs(c.z()) > limit)
                continue;
            v.centres.push_back(c);
            ++v.cells[cell_key(v.index(c.x()), v.index(c.y()), v.index(c.z()))];
        }
    (void)h;
    return v;
}

struct Peak {
    Vector3d centre;
    std::size_t votes = 0;
};

// The strongest vote peaks (3 x 3 x 3 cells summed), none within `radius` of
// a stronger one; each centre the mean of the votes near the peak cell.
std::vector<Peak> vote_peaks(const Votes& v, double radius, std::size_t max_peaks,
                             std::size_t min_votes) {
    struct Cell {
        std::int64_t x, y, z;
        std::size_t score;
    };
    std::vector<Cell> cells;
    cells.reserve(v.cells.size());
    for (const auto& [key, count] : v.cells) {
        (void)count;
        const std::int64_t x = ((key >> 42) & ((kCellRange << 1) - 1)) - kCellRange;
        const std::int64_t y = ((key >> 21) & ((kCellRange << 1) - 1)) - kCellRange;
        const std::int64_t z = (key & ((kCellRange << 1) - 1)) - kCellRange;
        std::size_t score = 0;
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz)
                    score += v.count(x + dx, y + dy, z + dz);
        if (score >= min_votes)
            cells.push_back({x, y, z, score});
    }
    std::sort(cells.begin(), cells.end(), [](const Cell& a, const Cell& b) {
        return a.score != b.score ? a.score > b.score
                                  : std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
    });
    std::vector<Peak> peaks;
    for (const Cell& c : cells) {
        if (peaks.size() >= max_peaks)
            break;
        const Vector3d at =
            (Vector3d(double(c.x), double(c.y), double(c.z)) + Vector3d::Constant(0.5)) * v.cell;
        if (std::any_of(peaks.begin(), peaks.end(),
                        [&](const Peak& p) { return (p.centre - at).norm() < radius; }))
            continue;
        Vector3d sum = Vector3d::Zero();
        std::size_t n = 0;
        for (const Vector3d& centre : v.centres)
            if ((centre - at).cwiseAbs().maxCoeff() < 1.5 * v.cell) {
                sum += centre;
                ++n;
            }
        peaks.push_back({n ? Vector3d(sum / double(n)) : at, c.score});
    }
    return peaks;
}

// Drops the points whose surface normal (from the points about r/8 either
// side, or nearer where those are not all usable, down to 2 px) is more than
// 20 degrees off the sphere's radius: where a bar or a stand meets the
// sphere, the points within the band of its shell are on the bar.
void drop_off_normal(const Image<float>& xyz, std::span<const std::uint8_t> usable,
                     const Vector3d& centre, double radius, double angle,
                     std::vector<std::uint32_t>& pixels, std::vector<Vec3>& points) {
    const int w = xyz.width(), h = xyz.height();
    const double min_cos = std::cos(20 * kPi / 180);
    std::size_t kept = 0;
    for (std::size_t k = 0; k < pixels.size(); ++k) {
        const std::size_t i = pixels[k];
        const int x = int(i % std::size_t(w)), y = int(i / std::size_t(w));
        const Vector3d p = to_eigen(points[k]);
        const int step = std::clamp(
            angle > 0 ? static_cast<int>(std::lround(radius / 8 / (angle * p.z()))) : 2, 2, 8);
        // Near a hole or an edge, shorter baselines (down to 2 px) in turn.
        bool keep = true;
        for (int s = step; s >= 2; s /= 2) {
            if (x < s || y < s || x + s >= w || y + s >= h)
                continue;
            const std::size_t l = i - std::size_t(s), r = i + std::size_t(s);
            const std::size_t u = i - std::size_t(s) * std::size_t(w),
                              d = i + std::size_t(s) * std::size_t(w);
            if (!usable[l] || !usable[r] || !usable[u] || !usable[d])
                continue;
            const Vector3d n =
                (point_at(xyz, r) - point_at(xyz, l)).cross(point_at(xyz, d) - point_at(xyz, u));
            const Vector3d radial = p - centre;
            keep = n.norm() > 0 && std::abs(n.dot(radial)) >= min_cos * n.norm() * radial.norm();
            break;
        }
        if (keep) {
            pixels[kept] = pixels[k];
            points[kept] = points[k];
            ++kept;
        }
    }
    pixels.resize(kept);
    points.resize(kept);
}

// Step 3 of the header for one peak; false when it is no sphere.
bool fit_peak(const Image<float>& xyz, std::span<const std::uint8_t> usable, const Peak& peak,
              double diameter, double angle, const ArtefactSearchOptions& options,
              FoundSphere& out) {
    const double radius = diameter / 2;
    std::vector<std::uint32_t> pixels;
    std::vector<Vec3> points;
    gather_shell(xyz, usable, peak.centre, radius, std::max(1.0, 0.15 * radius), pixels, points);
    if (points.size() < options.min_points)
        return false;
    const std::size_t gathered = points.size();
    try {
        FitOptions robust;
        robust.reject_sigma = 3;
        SphereFit fit = fit_sphere(points, robust);
        for (int round = 0; round < 2; ++round) {
            std::vector<double> used;
            for (std::size_t i = 0; i < points.size(); ++i)
                if (fit.fit.inlier[i])
                    used.push_back(fit.fit.residuals[i]);
            const double sigma = 1.4826 * median_abs(used);
            gather_shell(xyz, usable, to_eigen(fit.centre), fit.radius, std::max(5 * sigma, 0.05),
                         pixels, points);
            drop_off_normal(xyz, usable, to_eigen(fit.centre), fit.radius, angle, pixels, points);
            if (points.size() < options.min_points)
                return false;
            fit = fit_sphere(points);
        }
        if (!(std::abs(2 * fit.radius - diameter) <= std::max(1.0, 0.1 * diameter)))
            return false;
        out.figures = probing_figures(points, diameter);
    } catch (const FitError&) {
        return false;
    }
    out.pixels = std::move(pixels);
    out.points = std::move(points);
    out.coverage = hemisphere_coverage(out.points, out.figures.fit.centre);
    out.gathered = gathered;
    out.votes = peak.votes;
    return true;
}

} // namespace

std::vector<std::uint8_t> usable_points(const Image<float>& xyz,
                                        const ArtefactSearchOptions& options) {
    const int w = xyz.width(), h = xyz.height();
    const std::size_t n = xyz.pixel_count();
    std::vector<std::uint8_t> usable(n, 0), edge(n, 0);
    for (std::size_t i = 0; i < n; ++i)
        usable[i] = finite_at(xyz, i) ? 1 : 0;
    const double angle = pixel_angle(xyz);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
            if (!usable[i])
                continue;
            const double z = double(xyz.data()[3 * i + 2]);
            const double jump = options.depth_jump_footprints * angle * std::abs(z);
            const int nx[4] = {x - 1, x + 1, x, x}, ny[4] = {y, y, y - 1, y + 1};
            for (int k = 0; k < 4 && !edge[i]; ++k) {
                if (nx[k] < 0 || ny[k] < 0 || nx[k] >= w || ny[k] >= h) {
                    edge[i] = 1;
                    continue;
                }
                const std::size_t j = std::size_t(ny[k]) * std::size_t(w) + std::size_t(nx[k]);
                edge[i] = !usable[j] || std::abs(double(xyz.data()[3 * j + 2]) - z) > jump;
            }
        }
    dilate(edge, w, h, options.edge_margin_px);
    for (std::size_t i = 0; i < n; ++i)
        usable[i] = usable[i] && !edge[i];
    return usable;
}

double hemisphere_coverage(std::span<const Vec3> points, const Vec3& centre) {
    const Vector3d c = to_eigen(centre);
    if (!(c.norm() > 0))
        return 0;
    const Vector3d view = -c.normalized(); // from the centre towards the camera
    // A frame about the view direction.
    const Vector3d a =
        (std::abs(view.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY()).cross(view).normalized();
    const Vector3d b = view.cross(a);
    // Lambert's azimuthal equal-area projection maps the hemisphere onto a
    // disc of radius sqrt 2; a square grid over it has cells of equal area
    // on the sphere, about square everywhere.
    const double half = std::sqrt(2.0), cell = 2 * half / kCoverageGrid;
    auto inside = [&](int ix, int iy) {
        return std::hypot(-half + (ix + 0.5) * cell, -half + (iy + 0.5) * cell) <= half;
    };
    std::vector<std::uint8_t> hit(kCoverageGrid * kCoverageGrid, 0);
    for (const Vec3& p : points) {
        const Vector3d u = (to_eigen(p) - c).normalized();
        const double cos_view = u.dot(view);
        if (!(cos_view >= 0))
            continue;
        const double k = std::sqrt(2 / (1 + cos_view));
        const int ix =
            std::clamp(static_cast<int>((k * u.dot(a) + half) / cell), 0, kCoverageGrid - 1);
        const int iy =
            std::clamp(static_cast<int>((k * u.dot(b) + half) / cell), 0, kCoverageGrid - 1);
        if (inside(ix, iy))
            hit[std::size_t(iy * kCoverageGrid + ix)] = 1;
    }
    int cells = 0, covered = 0;
    for (int iy = 0; iy < kCoverageGrid; ++iy)
        for (int ix = 0; ix < kCoverageGrid; ++ix)
            if (inside(ix, iy)) {
                ++cells;
                covered += hit[std::size_t(iy * kCoverageGrid + ix)];
            }
    return double(covered) / double(cells);
}

std::vector<FoundSphere> find_spheres(const Image<float>& xyz, std::span<const std::uint8_t> usable,
                                      double diameter_mm, const ArtefactSearchOptions& options) {
    const double radius = diameter_mm / 2;
    const Votes votes = vote_centres(xyz, usable, radius);
    const double angle = pixel_angle(xyz);
    const std::vector<Peak> peaks =
        vote_peaks(votes, radius, options.max_candidates, options.min_votes);
    std::vector<FoundSphere> found;
    for (const Peak& peak : peaks) {
        FoundSphere sphere;
        if (!fit_peak(xyz, usable, peak, diameter_mm, angle, options, sphere))
            continue;
        // Two peaks of one sphere (its votes split): the better fit stays.
        const Vector3d c = to_eigen(sphere.figures.fit.centre);
        auto same = std::find_if(found.begin(), found.end(), [&](const FoundSphere& f) {
            return (to_eigen(f.figures.fit.centre) - c).norm() < radius;
        });
        if (same == found.end())
            found.push_back(std::move(sphere));
        else if (sphere.points.size() > same->points.size())
            *same = std::move(sphere);
    }
    return found;
}

} // namespace fpp::calib
