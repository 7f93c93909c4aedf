// Evaluation figures: guideline-style figures from fits, errors against the
// ground truth, cloud-to-cloud distances.

#include "fpp/calib/evaluation.hpp"

#include "fpp/error.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <span>
#include <stdexcept>

namespace fpp::calib {

namespace {

constexpr std::uint32_t kNoPoint = std::numeric_limits<std::uint32_t>::max();

bool finite3(const float* p) {
    return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

// For each camera pixel, the index of the cloud's point there (kNoPoint if none).
std::vector<std::uint32_t> pixel_lookup(const CloudPoints& cloud) {
    std::vector<std::uint32_t> lookup(cloud.organised.area(), kNoPoint);
    for (std::size_t i = 0; i < cloud.pixels.size(); ++i)
        lookup[cloud.pixels[i]] = static_cast<std::uint32_t>(i);
    return lookup;
}

// Used points ranked by |residual|; the guideline's share with the largest
// ones dropped, the rest refitted by `refit` (returning its FitResiduals).
template <class Refit>
TrimmedRange trimmed_range(std::span<const Vec3> points, const FitResiduals& fit, double fraction,
                           Refit&& refit) {
    std::vector<std::size_t> used;
    used.reserve(fit.used);
    for (std::size_t i = 0; i < points.size(); ++i)
        if (fit.inlier[i])
            used.push_back(i);
    TrimmedRange t;
    t.excluded = static_cast<std::size_t>(std::floor(fraction * static_cast<double>(used.size())));
    if (t.excluded == 0) {
        t.range = fit.max - fit.min;
        t.rms = fit.rms;
        return t;
    }
    std::nth_element(used.begin(), used.end() - static_cast<std::ptrdiff_t>(t.excluded), used.end(),
                     [&](std::size_t a, std::size_t b) {
                         return std::abs(fit.residuals[a]) < std::abs(fit.residuals[b]);
                     });
    std::vector<Vec3> kept;
    kept.reserve(used.size() - t.excluded);
    for (std::size_t k = 0; k + t.excluded < used.size(); ++k)
        kept.push_back(points[used[k]]);
    const FitResiduals again = refit(std::span<const Vec3>(kept));
    t.range = again.max - again.min;
    t.rms = again.rms;
    return t;
}

} // namespace

CloudPoints cloud_points(const PlyPoints& ply, const std::filesystem::path& origin) {
    CloudPoints c;
    const bool organised = ply.organised.area() > 0 && ply.pixel.size() == ply.size();
    if (organised) {
        c.organised = ply.organised;
        const std::size_t area = ply.organised.area();
        if (area > std::size_t{kNoPoint})
            throw InputError(origin, "obj_info organised_width/height",
                             "more pixels than a 32-bit index can number");
        std::vector<std::uint8_t> seen(area, 0);
        for (std::size_t i = 0; i < ply.size(); ++i) {
            const std::uint32_t p = ply.pixel[i];
            if (p >= area)
                throw InputError(origin, "pixel",
                                 "vertex " + std::to_string(i) + ": pixel index " +
                                     std::to_string(p) + " outside the organised " +
                                     std::to_string(ply.organised.width) + " x " +
                                     std::to_string(ply.organised.height) + " image");
            if (seen[p])
                throw InputError(origin, "pixel",
                                 "vertex " + std::to_string(i) + ": pixel index " +
                                     std::to_string(p) + " used by an earlier vertex too");
            seen[p] = 1;
        }
    }
    c.points.reserve(ply.size());
    if (organised)
        c.pixels.reserve(ply.size());
    for (std::size_t i = 0; i < ply.size(); ++i) {
        if (!std::isfinite(ply.x[i]) || !std::isfinite(ply.y[i]) || !std::isfinite(ply.z[i]))
            continue;
        c.points.push_back({double(ply.x[i]), double(ply.y[i]), double(ply.z[i])});
        if (organised)
            c.pixels.push_back(ply.pixel[i]);
    }
    return c;
}

CloudPoints cloud_points(const PointCloud& cloud) {
    if (cloud.xyz.channels() != 3)
        throw std::invalid_argument("cloud_points: xyz must have 3 channels");
    CloudPoints c;
    c.organised = cloud.size();
    const std::size_t n = cloud.xyz.pixel_count();
    const float* p = cloud.xyz.data();
    for (std::size_t i = 0; i < n; ++i, p += 3)
        if (finite3(p)) {
            c.points.push_back({double(p[0]), double(p[1]), double(p[2])});
            c.pixels.push_back(static_cast<std::uint32_t>(i));
        }
    return c;
}

ErrorStats error_stats(std::span<const double> values) {
    ErrorStats s;
    s.count = values.size();
    if (values.empty())
        return s;
    double sum = 0, sum2 = 0;
    s.min = std::numeric_limits<double>::infinity();
    s.max = -s.min;
    for (double v : values) {
        sum += v;
        sum2 += v * v;
        s.min = std::min(s.min, v);
        s.max = std::max(s.max, v);
    }
    const double n = static_cast<double>(values.size());
    s.mean = sum / n;
    s.rms = std::sqrt(sum2 / n);
    double var = 0;
    for (double v : values)
        var += (v - s.mean) * (v - s.mean);
    s.stddev = std::sqrt(var / n);
    s.max_abs = std::max(std::abs(s.min), std::abs(s.max));
    return s;
}

Image<float> values_image(const CloudPoints& cloud, std::span<const double> values) {
    if (!cloud.is_organised())
        throw std::invalid_argument("values_image: the cloud is not organised");
    if (values.size() != cloud.points.size())
        throw std::invalid_argument("values_image: one value per point expected");
    Image<float> image(cloud.organised, 1, std::numeric_limits<float>::quiet_NaN());
    float* out = image.data();
    for (std::size_t i = 0; i < values.size(); ++i)
        out[cloud.pixels[i]] = static_cast<float>(values[i]);
    return image;
}

// ---------------------------------------------------------------- guideline figures

FlatnessFigures flatness_figures(std::span<const Vec3> points, const FitOptions& options,
                                 double excluded_fraction) {
    FlatnessFigures f;
    f.fit = fit_plane(points, options);
    f.flatness = f.fit.fit.max - f.fit.fit.min;
    f.trimmed = trimmed_range(points, f.fit.fit, excluded_fraction,
                              [](std::span<const Vec3> kept) { return fit_plane(kept).fit; });
    return f;
}

ProbingFigures probing_figures(std::span<const Vec3> points, std::optional<double> nominal,
                               const FitOptions& options, double excluded_fraction) {
    ProbingFigures f;
    f.fit = fit_sphere(points, options);
    f.form = f.fit.fit.max - f.fit.fit.min;
    FitOptions plain = options;
    plain.reject_sigma = 0;
    f.form_trimmed =
        trimmed_range(points, f.fit.fit, excluded_fraction,
                      [&](std::span<const Vec3> kept) { return fit_sphere(kept, plain).fit; });
    f.diameter = 2 * f.fit.radius;
    if (nominal)
        f.size_error = f.diameter - *nominal;
    return f;
}

CylinderFigures cylinder_figures(std::span<const Vec3> points, std::optional<double> nominal,
                                 const FitOptions& options) {
    CylinderFigures f;
    f.fit = fit_cylinder(points, options);
    f.form = f.fit.fit.max - f.fit.fit.min;
    f.diameter = 2 * f.fit.radius;
    if (nominal)
        f.diameter_error = f.diameter - *nominal;
    return f;
}

BallBarFigures ball_bar_figures(std::span<const Vec3> points, std::optional<double> nominal_length,
                                std::optional<double> nominal_diameter, const FitOptions& options) {
    BallBarFigures f;
    f.fit = fit_ball_bar(points, options, &f.cluster);
    f.length = f.fit.distance;
    if (nominal_length)
        f.spacing_error = f.length - *nominal_length;
    f.form_first = f.fit.first.fit.max - f.fit.first.fit.min;
    f.form_second = f.fit.second.fit.max - f.fit.second.fit.min;
    if (nominal_diameter) {
        f.size_error_first = 2 * f.fit.first.radius - *nominal_diameter;
        f.size_error_second = 2 * f.fit.second.radius - *nominal_diameter;
    }
    return f;
}

// ---------------------------------------------------------------- ground truth

namespace {

// values[i] less the least-squares a + b x + c y at xy[i] (x, y centred and
// scaled to unit RMS, so the 3 x 3 normal equations are well conditioned).
// Fewer than 3 values or a degenerate layout: the values less their mean.
std::vector<double> without_planar_part(std::span<const double> values,
                                        std::span<const std::array<double, 2>> xy) {
    const std::size_t n = values.size();
    std::vector<double> out(values.begin(), values.end());
    if (n == 0)
        return out;
    double mx = 0, my = 0;
    for (const auto& p : xy) {
        mx += p[0];
        my += p[1];
    }
    mx /= double(n);
    my /= double(n);
    double ss = 0;
    for (const auto& p : xy)
        ss += (p[0] - mx) * (p[0] - mx) + (p[1] - my) * (p[1] - my);
    const double scale = ss > 0 ? 1.0 / std::sqrt(ss / double(n)) : 1.0;
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d r(1.0, (xy[i][0] - mx) * scale, (xy[i][1] - my) * scale);
        a += r * r.transpose();
        b += r * values[i];
    }
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(a);
    if (n >= 3 && ldlt.info() == Eigen::Success && ldlt.rcond() > 1e-12)
        c = ldlt.solve(b);
    else
        c[0] = b[0] / double(n);
    for (std::size_t i = 0; i < n; ++i)
        out[i] -= c[0] + c[1] * (xy[i][0] - mx) * scale + c[2] * (xy[i][1] - my) * scale;
    return out;
}

// The least-squares rigid motion of the compared points onto their truth
// (Umeyama without scale, about the centroids: conditioned for clouds
// hundreds of mm from the camera) and the distances left after it.
void fit_rigid_motion(const CloudPoints& cloud, const float* truth, TruthComparison& t) {
    if (t.compared < 3)
        return;
    Eigen::Matrix3Xd a(3, Eigen::Index(t.compared)), b(3, Eigen::Index(t.compared));
    Eigen::Index k = 0;
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
        const float* ref = truth + 3 * std::size_t{cloud.pixels[i]};
        if (!finite3(ref))
            continue;
        a.col(k) = Eigen::Vector3d(cloud.points[i][0], cloud.points[i][1], cloud.points[i][2]);
        b.col(k) = Eigen::Vector3d(ref[0], ref[1], ref[2]);
        ++k;
    }
    const Eigen::Matrix4d T = Eigen::umeyama(a, b, false);
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c)
            t.rigid_rotation[std::size_t(3 * r + c)] = R(r, c);
        t.rigid_translation[std::size_t(r)] = T(r, 3);
    }
    t.rigid_angle_rad = Eigen::AngleAxisd(R).angle();
    const Eigen::Matrix3Xd moved = (R * a).colwise() + T.topRightCorner<3, 1>();
    t.distance_rigid_values.resize(t.compared);
    for (Eigen::Index i = 0; i < a.cols(); ++i)
        t.distance_rigid_values[std::size_t(i)] = (moved.col(i) - b.col(i)).norm();
    t.distance_rigid = error_stats(t.distance_rigid_values);
}

} // namespace

TruthComparison compare_with_truth(const CloudPoints& cloud, const Image<float>& truth) {
    if (!cloud.is_organised())
        throw std::invalid_argument("compare_with_truth: the cloud is not organised");
    if (truth.channels() != 3 || truth.size() != cloud.organised)
        throw std::invalid_argument("compare_with_truth: the truth must be a 3-channel image of "
                                    "the cloud's organised size");
    TruthComparison t;
    const float* xyz = truth.data();
    for (std::size_t i = 0, n = truth.pixel_count(); i < n; ++i)
        t.truth_pixels += finite3(xyz + 3 * i) ? 1 : 0;
    t.dz_map = Image<float>(cloud.organised, 1, std::numeric_limits<float>::quiet_NaN());
    t.dz_values.reserve(cloud.points.size());
    std::vector<double> distances;
    distances.reserve(cloud.points.size());
    std::vector<std::array<double, 2>> true_xy;
    true_xy.reserve(cloud.points.size());
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
        const std::uint32_t pixel = cloud.pixels[i];
        const float* ref = xyz + 3 * std::size_t{pixel};
        if (!finite3(ref)) {
            ++t.no_surface;
            continue;
        }
        const Vec3& p = cloud.points[i];
        const double dx = p[0] - double(ref[0]), dy = p[1] - double(ref[1]),
                     dz = p[2] - double(ref[2]);
        t.dz_values.push_back(dz);
        true_xy.push_back({double(ref[0]), double(ref[1])});
        distances.push_back(std::sqrt(dx * dx + dy * dy + dz * dz));
        t.dz_map.data()[pixel] = static_cast<float>(dz);
    }
    t.compared = t.dz_values.size();
    t.coverage =
        t.truth_pixels ? static_cast<double>(t.compared) / static_cast<double>(t.truth_pixels) : 0;
    t.dz = error_stats(t.dz_values);
    t.distance = error_stats(distances);
    t.dz_shape = error_stats(without_planar_part(t.dz_values, true_xy));
    fit_rigid_motion(cloud, xyz, t);
    return t;
}

// ---------------------------------------------------------------- cloud to cloud

CloudDistance compare_per_pixel(const CloudPoints& first, const CloudPoints& second) {
    if (!first.is_organised() || !second.is_organised())
        throw std::invalid_argument("compare_per_pixel: both clouds must be organised");
    if (first.organised != second.organised)
        throw std::invalid_argument("compare_per_pixel: the clouds' organised sizes differ");
    CloudDistance d;
    d.per_pixel = true;
    const std::vector<std::uint32_t> lookup = pixel_lookup(second);
    d.dz_map = Image<float>(first.organised, 1, std::numeric_limits<float>::quiet_NaN());
    d.values.reserve(first.points.size());
    std::vector<double> distances;
    distances.reserve(first.points.size());
    for (std::size_t i = 0; i < first.points.size(); ++i) {
        const std::uint32_t pixel = first.pixels[i];
        const std::uint32_t j = lookup[pixel];
        if (j == kNoPoint) {
            ++d.only_first;
            continue;
        }
        const Vec3& a = first.points[i];
        const Vec3& b = second.points[j];
        const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
        d.values.push_back(dz);
        distances.push_back(std::sqrt(dx * dx + dy * dy + dz * dz));
        d.dz_map.data()[pixel] = static_cast<float>(dz);
    }
    d.matched = d.values.size();
    d.only_second = second.points.size() - d.matched;
    d.dz = error_stats(d.values);
    d.distance = error_stats(distances);
    return d;
}

CloudDistance compare_nearest(const CloudPoints& first, const CloudPoints& second,
                              double max_distance) {
    if (second.points.empty())
        throw std::invalid_argument("compare_nearest: the second cloud has no points");
    CloudDistance d;
    const PointIndex index(second.points);
    d.values.reserve(first.points.size());
    const double limit2 = max_distance * max_distance;
    for (const Vec3& p : first.points) {
        double d2 = 0;
        index.nearest(p, &d2);
        if (d2 > limit2) {
            ++d.only_first;
            continue;
        }
        d.values.push_back(std::sqrt(d2));
    }
    d.matched = d.values.size();
    d.distance = error_stats(d.values);
    return d;
}

// ---------------------------------------------------------------- figures table

std::string figures_csv(const std::vector<Figure>& figures) {
    std::string s = "name,value,unit\n";
    for (const Figure& f : figures) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.9g", f.value);
        s += f.name + "," + buf + "," + f.unit + "\n";
    }
    return s;
}

} // namespace fpp::calib
