// Finding a certified flat plate among other planes (see
// fpp/calib/artefact_search.hpp, find_plane).

#include "fpp/calib/artefact_search.hpp"

#include "organised_points.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

namespace fpp::calib {

namespace {

using namespace organised;

std::string mm_text(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f", v);
    return text;
}

// The largest 4-connected patch of `pixels` in a `w` x `h` image.
std::vector<std::uint32_t> largest_patch(const std::vector<std::uint32_t>& pixels, int w, int h) {
    std::vector<std::int32_t> label(std::size_t(w) * std::size_t(h), -1);
    for (std::size_t k = 0; k < pixels.size(); ++k)
        label[pixels[k]] = 0;
    std::vector<std::uint32_t> best, patch, stack;
    std::int32_t next = 1;
    for (const std::uint32_t start : pixels) {
        if (label[start] != 0)
            continue;
        patch.clear();
        stack.assign(1, start);
        label[start] = next;
        while (!stack.empty()) {
            const std::uint32_t i = stack.back();
            stack.pop_back();
            patch.push_back(i);
            const int x = int(i % std::uint32_t(w)), y = int(i / std::uint32_t(w));
            const int nx[4] = {x - 1, x + 1, x, x}, ny[4] = {y, y, y - 1, y + 1};
            for (int k = 0; k < 4; ++k) {
                if (nx[k] < 0 || ny[k] < 0 || nx[k] >= w || ny[k] >= h)
                    continue;
                const std::uint32_t j =
                    std::uint32_t(ny[k]) * std::uint32_t(w) + std::uint32_t(nx[k]);
                if (label[j] == 0) {
                    label[j] = next;
                    stack.push_back(j);
                }
            }
        }
        ++next;
        if (patch.size() > best.size())
            best.swap(patch);
    }
    std::sort(best.begin(), best.end());
    return best;
}

// Extents of points along their two principal directions, larger first.
void principal_extents(const std::vector<Vec3>& points, double extent[2]) {
    Vector3d mean = Vector3d::Zero();
    for (const Vec3& p : points)
        mean += to_eigen(p);
    mean /= double(points.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const Vec3& p : points) {
        const Vector3d d = to_eigen(p) - mean;
        cov += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(cov);
    for (int k = 0; k < 2; ++k) {
        const Vector3d axis = eigen.eigenvectors().col(2 - k); // largest eigenvalues last
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (const Vec3& p : points) {
            const double t = (to_eigen(p) - mean).dot(axis);
            lo = std::min(lo, t);
            hi = std::max(hi, t);
        }
        extent[k] = hi - lo;
    }
}

// The pool's points within `band` of the plane through `point` with unit `normal`.
void gather_plane(const Image<float>& xyz, const std::vector<std::uint32_t>& pool,
                  const Vector3d& point, const Vector3d& normal, double band,
                  std::vector<std::uint32_t>& pixels, std::vector<Vec3>& points) {
    pixels.clear();
    points.clear();
    for (const std::uint32_t i : pool) {
        const Vector3d p = point_at(xyz, i);
        if (std::abs((p - point).dot(normal)) < band) {
            pixels.push_back(i);
            points.push_back(to_vec(p));
        }
    }
}

// The plane of most points among the pool (RANSAC, 1 mm band, seeded: the
// same cloud gives the same plane); false when none holds `min_points`.
bool ransac_plane(const Image<float>& xyz, const std::vector<std::uint32_t>& pool,
                  std::size_t min_points, Vector3d& point, Vector3d& normal) {
    constexpr int kTrials = 300;
    constexpr double kBand = 1.0;
    const std::size_t stride = std::max<std::size_t>(1, pool.size() / 20000);
    std::mt19937 rng(1);
    std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
    std::size_t best = 0;
    for (int trial = 0; trial < kTrials; ++trial) {
        const Vector3d a = point_at(xyz, pool[pick(rng)]), b = point_at(xyz, pool[pick(rng)]),
                       c = point_at(xyz, pool[pick(rng)]);
        Vector3d n = (b - a).cross(c - a);
        if (!(n.norm() > 1e-6))
            continue;
        n.normalize();
        std::size_t count = 0;
        for (std::size_t k = 0; k < pool.size(); k += stride)
            count += std::abs((point_at(xyz, pool[k]) - a).dot(n)) < kBand ? 1 : 0;
        if (count > best) {
            best = count;
            point = a;
            normal = n;
        }
    }
    return best * stride >= min_points;
}

} // namespace

FoundPlane find_plane(const Image<float>& xyz, std::span<const std::uint8_t> usable,
                      double width_mm, double height_mm, const ArtefactSearchOptions& options) {
    std::vector<std::uint32_t> pool;
    for (std::size_t i = 0; i < usable.size(); ++i)
        if (usable[i])
            pool.push_back(static_cast<std::uint32_t>(i));
    const double longer = std::max(width_mm, height_mm), shorter = std::min(width_mm, height_mm);
    constexpr double kExtentSlackMm = 5;
    std::string seen;
    for (int attempt = 0; attempt < 4 && pool.size() >= options.min_points; ++attempt) {
        Vector3d point, normal;
        if (!ransac_plane(xyz, pool, options.min_points, point, normal))
            break;
        std::vector<std::uint32_t> pixels;
        std::vector<Vec3> points;
        gather_plane(xyz, pool, point, normal, 1.0, pixels, points);
        PlaneFit fit;
        try {
            FitOptions robust;
            robust.reject_sigma = 3;
            fit = fit_plane(points, robust);
            for (int round = 0; round < 2; ++round) {
                std::vector<double> used;
                for (std::size_t i = 0; i < points.size(); ++i)
                    if (fit.fit.inlier[i])
                        used.push_back(fit.fit.residuals[i]);
                gather_plane(xyz, pool, to_eigen(fit.point), to_eigen(fit.normal),
                             std::max(5 * 1.4826 * median_abs(used), 0.05), pixels, points);
                if (points.size() < options.min_points)
                    break;
                fit = fit_plane(points);
            }
        } catch (const FitError&) {
            break;
        }
        const std::vector<std::uint32_t> patch = largest_patch(pixels, xyz.width(), xyz.height());
        FoundPlane found;
        for (const std::uint32_t i : patch)
            found.points.push_back(to_vec(point_at(xyz, i)));
        if (found.points.size() >= options.min_points) {
            principal_extents(found.points, found.extent_mm);
            if (found.extent_mm[0] <= longer + kExtentSlackMm &&
                found.extent_mm[1] <= shorter + kExtentSlackMm) {
                found.pixels = patch;
                found.figures = flatness_figures(found.points);
                return found;
            }
            seen += (seen.empty() ? "" : ", ") + mm_text(found.extent_mm[0]) + " x " +
                    mm_text(found.extent_mm[1]) + " mm";
        }
        // Not the plate (a wall, a table): look among the other points.
        std::vector<std::uint8_t> taken(usable.size(), 0);
        for (const std::uint32_t i : pixels)
            taken[i] = 1;
        std::erase_if(pool, [&](std::uint32_t i) { return taken[i] != 0; });
    }
    throw FitError("no flat of " + mm_text(width_mm) + " x " + mm_text(height_mm) + " mm in view" +
                   (seen.empty() ? std::string(" (no plane found)")
                                 : "; the planes found are larger: " + seen +
                                       " (a wall or a table? the plate must be seen apart)"));
}

} // namespace fpp::calib
