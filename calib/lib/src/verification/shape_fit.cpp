// Least-squares fits of planes, spheres, cylinders and ball-bars; k-d tree.

#include "fpp/calib/shape_fit.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>

namespace fpp::calib {

namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Points = std::vector<Vector3d>;

constexpr double kPi = 3.14159265358979323846;
// A fitted radius beyond this many RMS spreads of the points means the data
// show no curvature (a flat patch): the radius is not determined.
constexpr double kMaxRadiusOverSpread = 1000.0;

Vector3d to_eigen(const Vec3& v) {
    return {v[0], v[1], v[2]};
}
Vec3 to_vec(const Vector3d& v) {
    return {v.x(), v.y(), v.z()};
}

std::string number(double v, int digits) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", digits, v);
    return buf;
}

std::string vector_text(const Vector3d& v, int digits) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "(%.*f, %.*f, %.*f)", digits, v.x(), digits, v.y(), digits,
                  v.z());
    return buf;
}

// The points centred on their centroid and divided by their RMS distance
// from it (dimensionless, spread 1).
struct Conditioned {
    Vector3d centroid = Vector3d::Zero();
    double scale = 1;
    Points q;
    Vector3d to_world(const Vector3d& p) const { return centroid + scale * p; }
};

Conditioned condition(std::span<const Vec3> points, const char* shape, std::size_t minimum) {
    if (points.size() < minimum)
        throw FitError(std::string(shape) + " fit: " + std::to_string(points.size()) +
                       " points; at least " + std::to_string(minimum) + " are needed");
    Conditioned c;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Vec3& p = points[i];
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
            throw FitError(std::string(shape) + " fit: point " + std::to_string(i) +
                           " has a non-finite coordinate");
        c.centroid += to_eigen(p);
    }
    c.centroid /= static_cast<double>(points.size());
    double sum = 0;
    for (const Vec3& p : points)
        sum += (to_eigen(p) - c.centroid).squaredNorm();
    c.scale = std::sqrt(sum / static_cast<double>(points.size()));
    if (!(c.scale > 0) || !std::isfinite(c.scale))
        throw FitError(std::string(shape) + " fit: all " + std::to_string(points.size()) +
                       " points coincide");
    c.q.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        c.q[i] = (to_eigen(points[i]) - c.centroid) / c.scale;
    return c;
}

// Fit on the used points, iterative outlier rejection, residuals of all
// points. `fit(used, start, iterations)` returns the model in conditioned
// coordinates; `residual(model, q)` the signed conditioned residual.
template <class Model, class Fit, class Residual>
Model fit_with_rejection(const Conditioned& c, const FitOptions& options, std::size_t minimum,
                         Fit&& fit, Residual&& residual, FitResiduals& out) {
    const std::size_t n = c.q.size();
    out.inlier.assign(n, 1);
    out.residuals.resize(n);
    int iterations = 0;
    Model model = fit(c.q, static_cast<const Model*>(nullptr), iterations);
    auto evaluate = [&] {
        for (std::size_t i = 0; i < n; ++i)
            out.residuals[i] = residual(model, c.q[i]);
    };
    evaluate();
    out.rejection_rounds = 0;
    if (options.reject_sigma > 0) {
        std::vector<std::uint8_t> next(n);
        Points used;
        used.reserve(n);
        for (int round = 0; round < options.max_rejection_rounds; ++round) {
            double sum = 0;
            std::size_t count = 0;
            for (std::size_t i = 0; i < n; ++i)
                if (out.inlier[i]) {
                    sum += out.residuals[i] * out.residuals[i];
                    ++count;
                }
            // A floor keeps an exact fit from rejecting rounding noise.
            const double limit =
                std::max(options.reject_sigma * std::sqrt(sum / static_cast<double>(count)), 1e-12);
            std::size_t kept = 0;
            for (std::size_t i = 0; i < n; ++i) {
                next[i] = std::abs(out.residuals[i]) <= limit ? 1 : 0;
                kept += next[i];
            }
            if (next == out.inlier || kept < minimum)
                break;
            out.inlier = next;
            used.clear();
            for (std::size_t i = 0; i < n; ++i)
                if (out.inlier[i])
                    used.push_back(c.q[i]);
            model = fit(used, &model, iterations);
            evaluate();
            ++out.rejection_rounds;
        }
    }
    out.iterations = iterations;
    out.used = 0;
    double sum = 0;
    out.min = std::numeric_limits<double>::infinity();
    out.max = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n; ++i) {
        out.residuals[i] *= c.scale;
        if (!out.inlier[i])
            continue;
        ++out.used;
        sum += out.residuals[i] * out.residuals[i];
        out.min = std::min(out.min, out.residuals[i]);
        out.max = std::max(out.max, out.residuals[i]);
    }
    out.rejected = n - out.used;
    out.rms = std::sqrt(sum / static_cast<double>(out.used));
    return model;
}

std::string residual_text(const FitResiduals& f, const FitOptions& options) {
    std::string s = "RMS " + number(f.rms, 4) + " mm, residuals " + number(f.min, 4) + " .. " +
                    number(f.max, 4) + " mm over " + std::to_string(f.used) + " points";
    if (options.reject_sigma > 0)
        s += " (" + std::to_string(f.rejected) + " rejected at " + number(options.reject_sigma, 1) +
             " sigma in " + std::to_string(f.rejection_rounds) + " rounds)";
    if (f.iterations > 0)
        s += ", " + std::to_string(f.iterations) + " iterations";
    return s;
}

// An orthonormal basis whose third column is the unit vector a.
Matrix3d basis_around(const Vector3d& a) {
    const Vector3d helper = std::abs(a.x()) < 0.6 ? Vector3d::UnitX() : Vector3d::UnitY();
    const Vector3d u = helper.cross(a).normalized();
    Matrix3d U;
    U.col(0) = u;
    U.col(1) = a.cross(u);
    U.col(2) = a;
    return U;
}

// Principal directions of the points about their centroid, by decreasing
// variance (columns), and the variances.
struct Principal {
    Vector3d mean;
    Matrix3d directions;
    Vector3d variances;
};

Principal principal_axes(const Points& q) {
    Principal p;
    p.mean = Vector3d::Zero();
    for (const Vector3d& v : q)
        p.mean += v;
    p.mean /= static_cast<double>(q.size());
    Matrix3d scatter = Matrix3d::Zero();
    for (const Vector3d& v : q) {
        const Vector3d d = v - p.mean;
        scatter.noalias() += d * d.transpose();
    }
    scatter /= static_cast<double>(q.size());
    const Eigen::SelfAdjointEigenSolver<Matrix3d> eig(scatter);
    // Eigen sorts increasing; reverse to decreasing.
    for (int k = 0; k < 3; ++k) {
        p.directions.col(k) = eig.eigenvectors().col(2 - k);
        p.variances[k] = std::max(0.0, eig.eigenvalues()[2 - k]);
    }
    return p;
}

// ---------------------------------------------------------------- plane

struct PlaneModel {
    Vector3d point;
    Vector3d normal;
};

PlaneModel plane_core(const Points& q) {
    Vector3d mean = Vector3d::Zero();
    for (const Vector3d& v : q)
        mean += v;
    mean /= static_cast<double>(q.size());
    Eigen::MatrixXd a(static_cast<Eigen::Index>(q.size()), 3);
    for (std::size_t i = 0; i < q.size(); ++i)
        a.row(static_cast<Eigen::Index>(i)) = (q[i] - mean).transpose();
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinV);
    const Eigen::VectorXd& s = svd.singularValues();
    if (!(s(1) > 1e-9 * s(0)))
        throw FitError("plane fit: the " + std::to_string(q.size()) +
                       " points are collinear; a plane is not determined");
    const Eigen::MatrixXd& v = svd.matrixV();
    return {mean, Vector3d(v(0, 2), v(1, 2), v(2, 2)).normalized()};
}

double plane_residual(const PlaneModel& m, const Vector3d& q) {
    return (q - m.point).dot(m.normal);
}

// ---------------------------------------------------------------- sphere

struct SphereModel {
    Vector3d centre;
    double radius;
};

double sphere_cost(const Points& q, const SphereModel& m) {
    double sum = 0;
    for (const Vector3d& v : q) {
        const double e = (v - m.centre).norm() - m.radius;
        sum += e * e;
    }
    return sum;
}

SphereModel sphere_algebraic(const Points& q) {
    // |q|^2 = 2 c.q + d, d = r^2 - |c|^2; normal equations in the unknowns (c, d).
    Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
    Eigen::Vector4d atb = Eigen::Vector4d::Zero();
    for (const Vector3d& v : q) {
        const Eigen::Vector4d row(2 * v.x(), 2 * v.y(), 2 * v.z(), 1.0);
        ata.noalias() += row * row.transpose();
        atb += row * v.squaredNorm();
    }
    const Eigen::JacobiSVD<Eigen::Matrix4d> svd(ata, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Vector4d s = svd.singularValues();
    if (!(s[3] > 1e-13 * s[0]))
        throw FitError("sphere fit: the " + std::to_string(q.size()) +
                       " points lie on a plane or a line; a sphere is not determined");
    const Eigen::Vector4d x = svd.solve(atb);
    const Vector3d c = x.head<3>();
    const double r2 = x[3] + c.squaredNorm();
    if (!(r2 > 0) || !std::isfinite(r2))
        throw FitError("sphere fit: the algebraic start has no real radius (points not on a "
                       "sphere)");
    return {c, std::sqrt(r2)};
}

SphereModel sphere_core(const Points& q, const SphereModel* start, int max_iterations,
                        int& iterations) {
    SphereModel m = start ? *start : sphere_algebraic(q);
    double cost = sphere_cost(q, m);
    double lambda = 1e-3;
    iterations = 0;
    for (int it = 0; it < max_iterations; ++it) {
        Eigen::Matrix4d jtj = Eigen::Matrix4d::Zero();
        Eigen::Vector4d jte = Eigen::Vector4d::Zero();
        for (const Vector3d& v : q) {
            const Vector3d d = v - m.centre;
            const double dist = d.norm();
            Eigen::Vector4d j(0, 0, 0, -1);
            if (dist > 0)
                j.head<3>() = -d / dist;
            jtj.noalias() += j * j.transpose();
            jte += j * (dist - m.radius);
        }
        bool accepted = false;
        while (lambda < 1e12) {
            Eigen::Matrix4d a = jtj;
            a.diagonal() *= 1 + lambda;
            const Eigen::Vector4d delta = a.ldlt().solve(-jte);
            const SphereModel next{m.centre + delta.head<3>(), m.radius + delta[3]};
            const double next_cost = next.radius > 0 ? sphere_cost(q, next) : cost * 2 + 1;
            if (std::isfinite(next_cost) && next_cost < cost) {
                const double gain = cost - next_cost;
                m = next;
                accepted = true;
                lambda = std::max(lambda * 0.1, 1e-12);
                ++iterations;
                if (delta.norm() < 1e-12 * (1 + m.centre.norm() + m.radius) ||
                    gain < 1e-15 * cost) {
                    return m;
                }
                cost = next_cost;
                break;
            }
            lambda *= 10;
        }
        if (!accepted)
            break; // no step lowers the cost: at the minimum
    }
    return m;
}

// ---------------------------------------------------------------- cylinder

struct CylinderModel {
    Vector3d point; // on the axis
    Vector3d axis;  // unit
    double radius;
};

double cylinder_residual(const CylinderModel& m, const Vector3d& q) {
    return (q - m.point).cross(m.axis).norm() - m.radius;
}

double cylinder_cost(const Points& q, const CylinderModel& m) {
    double sum = 0;
    for (const Vector3d& v : q) {
        const double e = cylinder_residual(m, v);
        sum += e * e;
    }
    return sum;
}

// The axis point nearest to the origin (the conditioned centroid).
void recentre(CylinderModel& m) {
    m.point -= m.point.dot(m.axis) * m.axis;
}

// Levenberg-Marquardt in Forbes' local parametrisation: in the frame U whose
// z axis is the current axis (origin on it), the axis passes through
// (x0, y0, 0) with direction (a, b, 1); to first order the distance of
// (x, y, z) from it is rho - (x x0 + y y0 + a x z + b y z) / rho.
CylinderModel cylinder_lm(const Points& q, CylinderModel m, int max_iterations, int& iterations) {
    double cost = cylinder_cost(q, m);
    double lambda = 1e-3;
    iterations = 0;
    using Vector5d = Eigen::Matrix<double, 5, 1>;
    using Matrix5d = Eigen::Matrix<double, 5, 5>;
    for (int it = 0; it < max_iterations; ++it) {
        const Matrix3d u = basis_around(m.axis);
        Matrix5d jtj = Matrix5d::Zero();
        Vector5d jte = Vector5d::Zero();
        for (const Vector3d& v : q) {
            const Vector3d w = u.transpose() * (v - m.point);
            const double rho = std::hypot(w.x(), w.y());
            Vector5d j;
            if (rho > 0)
                j << -w.x() / rho, -w.y() / rho, -w.x() * w.z() / rho, -w.y() * w.z() / rho, -1;
            else
                j << 0, 0, 0, 0, -1;
            jtj.noalias() += j * j.transpose();
            jte += j * (rho - m.radius);
        }
        bool accepted = false;
        while (lambda < 1e12) {
            Matrix5d a = jtj;
            a.diagonal() *= 1 + lambda;
            const Vector5d delta = a.ldlt().solve(-jte);
            CylinderModel next;
            next.point = m.point + u * Vector3d(delta[0], delta[1], 0);
            next.axis = (u * Vector3d(delta[2], delta[3], 1)).normalized();
            next.radius = m.radius + delta[4];
            recentre(next);
            const double next_cost =
                next.radius > 0 && next.axis.allFinite() ? cylinder_cost(q, next) : cost * 2 + 1;
            if (std::isfinite(next_cost) && next_cost < cost) {
                const double gain = cost - next_cost;
                m = next;
                accepted = true;
                lambda = std::max(lambda * 0.1, 1e-12);
                ++iterations;
                if (delta.norm() < 1e-12 * (1 + m.radius) || gain < 1e-15 * cost)
                    return m;
                cost = next_cost;
                break;
            }
            lambda *= 10;
        }
        if (!accepted)
            break;
    }
    return m;
}

// Every k-th point, at most `limit` of them.
Points subsample(const Points& q, std::size_t limit) {
    if (q.size() <= limit)
        return q;
    const std::size_t stride = (q.size() + limit - 1) / limit;
    Points s;
    s.reserve(q.size() / stride + 1);
    for (std::size_t i = 0; i < q.size(); i += stride)
        s.push_back(q[i]);
    return s;
}

// The direction most orthogonal to the local surface normals (a cylinder's
// normals all meet its axis at right angles), or nothing if there are too
// few points for neighbourhoods.
std::optional<Vector3d> axis_from_normals(const Points& sample) {
    constexpr std::size_t kNeighbours = 12;
    if (sample.size() < 2 * kNeighbours)
        return std::nullopt;
    std::vector<Vec3> points(sample.size());
    for (std::size_t i = 0; i < sample.size(); ++i)
        points[i] = to_vec(sample[i]);
    const PointIndex index(points);
    std::vector<std::pair<double, std::size_t>> near;
    near.reserve(kNeighbours + 1);
    Matrix3d normals = Matrix3d::Zero();
    for (const Vec3& p : points) {
        index.nearest_k(p, kNeighbours, near);
        Vector3d mean = Vector3d::Zero();
        for (const auto& [d2, i] : near)
            mean += sample[i];
        mean /= static_cast<double>(near.size());
        Matrix3d scatter = Matrix3d::Zero();
        for (const auto& [d2, i] : near) {
            const Vector3d d = sample[i] - mean;
            scatter.noalias() += d * d.transpose();
        }
        const Eigen::SelfAdjointEigenSolver<Matrix3d> eig(scatter);
        const Vector3d n = eig.eigenvectors().col(0);
        normals.noalias() += n * n.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Matrix3d> eig(normals);
    return eig.eigenvectors().col(0);
}

// Circle through the points projected along `axis` (algebraic fit), as a
// cylinder start; nothing if the projection shows no circle.
std::optional<CylinderModel> cylinder_start(const Points& q, const Vector3d& axis) {
    const Matrix3d u = basis_around(axis.normalized());
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    for (const Vector3d& v : q) {
        const double x = u.col(0).dot(v), y = u.col(1).dot(v);
        const Eigen::Vector3d row(2 * x, 2 * y, 1.0);
        ata.noalias() += row * row.transpose();
        atb += row * (x * x + y * y);
    }
    // Symmetric 3 x 3: eigen-decomposition (= SVD); a near-null direction
    // means the projected points lie on a line.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(ata);
    const Eigen::Vector3d values = eig.eigenvalues();
    if (!(values[0] > 1e-13 * values[2]))
        return std::nullopt;
    const Eigen::Matrix3d vectors = eig.eigenvectors();
    const Eigen::Vector3d x = vectors * (vectors.transpose() * atb).cwiseQuotient(values);
    const double r2 = x[2] + x[0] * x[0] + x[1] * x[1];
    if (!(r2 > 0) || !std::isfinite(r2) || std::sqrt(r2) > kMaxRadiusOverSpread)
        return std::nullopt;
    CylinderModel m{x[0] * u.col(0) + x[1] * u.col(1), u.col(2), std::sqrt(r2)};
    recentre(m);
    return m;
}

CylinderModel cylinder_core(const Points& q, const CylinderModel* start, int max_iterations,
                            int& iterations) {
    if (start)
        return cylinder_lm(q, *start, max_iterations, iterations);
    const Principal pca = principal_axes(q);
    if (!(pca.variances[1] > 1e-12 * pca.variances[0]))
        throw FitError("cylinder fit: the " + std::to_string(q.size()) +
                       " points are collinear; a cylinder is not determined");
    const Points sample = subsample(q, 4000);
    std::vector<Vector3d> axes;
    if (const auto normal_axis = axis_from_normals(sample))
        axes.push_back(*normal_axis);
    for (int k = 0; k < 3; ++k)
        axes.push_back(pca.directions.col(k));
    // Each start refined on a subsample; the best one on all points.
    const Points trial_subsample = q.size() > 20000 ? subsample(q, 20000) : Points{};
    const Points& trial_points = trial_subsample.empty() ? q : trial_subsample;
    std::optional<CylinderModel> best;
    double best_cost = std::numeric_limits<double>::infinity();
    for (const Vector3d& axis : axes) {
        const auto init = cylinder_start(sample, axis);
        if (!init)
            continue;
        int unused = 0;
        const CylinderModel m = cylinder_lm(trial_points, *init, max_iterations, unused);
        const double cost = cylinder_cost(trial_points, m);
        if (m.radius < kMaxRadiusOverSpread && cost < best_cost) {
            best_cost = cost;
            best = m;
        }
    }
    if (!best)
        throw FitError("cylinder fit: no start found; the " + std::to_string(q.size()) +
                       " points show no circular cross-section (flat or irregular)");
    // A cylinder has a plane as its limit (infinite radius): one that fits
    // worse than the plane is a spurious minimum, not a measurement.
    const double plane_cost =
        principal_axes(trial_points).variances[2] * static_cast<double>(trial_points.size());
    if (!(best_cost < plane_cost))
        throw FitError("cylinder fit: no cylinder fits the " + std::to_string(q.size()) +
                       " points better than a plane; they show no curvature (a flat patch?)");
    return cylinder_lm(q, *best, max_iterations, iterations);
}

} // namespace

// ---------------------------------------------------------------- public fits

PlaneFit fit_plane(std::span<const Vec3> points, const FitOptions& options) {
    const Conditioned c = condition(points, "plane", 3);
    PlaneFit result;
    const PlaneModel m = fit_with_rejection<PlaneModel>(
        c, options, 3, [](const Points& q, const PlaneModel*, int&) { return plane_core(q); },
        plane_residual, result.fit);
    Vector3d normal = m.normal;
    const Vector3d point = c.to_world(m.point);
    // Normal towards the camera centre: positive residual = nearer the camera.
    const bool flip = normal.dot(-point) < 0;
    if (flip) {
        normal = -normal;
        for (double& r : result.fit.residuals)
            r = -r;
        std::swap(result.fit.min, result.fit.max);
        result.fit.min = -result.fit.min;
        result.fit.max = -result.fit.max;
    }
    result.point = to_vec(point);
    result.normal = to_vec(normal);
    result.fit.message = "plane: normal " + vector_text(normal, 6) + ", point " +
                         vector_text(point, 3) + " mm; " + residual_text(result.fit, options);
    return result;
}

SphereFit fit_sphere(std::span<const Vec3> points, const FitOptions& options) {
    const Conditioned c = condition(points, "sphere", 4);
    SphereFit result;
    const SphereModel m = fit_with_rejection<SphereModel>(
        c, options, 4,
        [&](const Points& q, const SphereModel* start, int& iterations) {
            return sphere_core(q, start, options.max_iterations, iterations);
        },
        [](const SphereModel& s, const Vector3d& q) { return (q - s.centre).norm() - s.radius; },
        result.fit);
    if (!(m.radius < kMaxRadiusOverSpread) || !m.centre.allFinite())
        throw FitError("sphere fit: the fitted radius is " + number(m.radius * c.scale, 1) +
                       " mm, over " + number(kMaxRadiusOverSpread, 0) +
                       " times the points' spread: they show no curvature (a flat patch?)");
    result.centre = to_vec(c.to_world(m.centre));
    result.radius = m.radius * c.scale;
    result.fit.message = "sphere: diameter " + number(2 * result.radius, 4) + " mm, centre " +
                         vector_text(c.to_world(m.centre), 4) + " mm; " +
                         residual_text(result.fit, options);
    return result;
}

CylinderFit fit_cylinder(std::span<const Vec3> points, const FitOptions& options) {
    const Conditioned c = condition(points, "cylinder", 5);
    CylinderFit result;
    const CylinderModel m = fit_with_rejection<CylinderModel>(
        c, options, 5,
        [&](const Points& q, const CylinderModel* start, int& iterations) {
            return cylinder_core(q, start, options.max_iterations, iterations);
        },
        cylinder_residual, result.fit);
    if (!(m.radius < kMaxRadiusOverSpread) || !m.point.allFinite() || !m.axis.allFinite())
        throw FitError("cylinder fit: the fitted radius is " + number(m.radius * c.scale, 1) +
                       " mm, over " + number(kMaxRadiusOverSpread, 0) +
                       " times the points' spread: they show no curvature (a flat patch?)");
    // Arc and length covered by the used points.
    const Matrix3d u = basis_around(m.axis);
    std::vector<double> angles;
    angles.reserve(result.fit.used);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t i = 0; i < c.q.size(); ++i) {
        if (!result.fit.inlier[i])
            continue;
        const Vector3d w = u.transpose() * (c.q[i] - m.point);
        angles.push_back(std::atan2(w.y(), w.x()));
        lo = std::min(lo, w.z());
        hi = std::max(hi, w.z());
    }
    std::sort(angles.begin(), angles.end());
    double gap = angles.front() + 2 * kPi - angles.back();
    for (std::size_t i = 1; i < angles.size(); ++i)
        gap = std::max(gap, angles[i] - angles[i - 1]);
    result.arc_degrees = (2 * kPi - gap) * 180 / kPi;
    result.length = (hi - lo) * c.scale;
    result.axis_point = to_vec(c.to_world(m.point));
    result.axis = to_vec(m.axis);
    result.radius = m.radius * c.scale;
    result.fit.message =
        "cylinder: diameter " + number(2 * result.radius, 4) + " mm, axis " +
        vector_text(m.axis, 6) + " through " + vector_text(c.to_world(m.point), 3) + " mm, " +
        number(result.arc_degrees, 1) + " degrees of arc, " + number(result.length, 1) +
        " mm long; " + residual_text(result.fit, options);
    return result;
}

BallBarFit fit_ball_bar(std::span<const Vec3> first, std::span<const Vec3> second,
                        const FitOptions& options) {
    BallBarFit bar;
    try {
        bar.first = fit_sphere(first, options);
    } catch (const FitError& e) {
        throw FitError(std::string("ball-bar, first sphere: ") + e.what());
    }
    try {
        bar.second = fit_sphere(second, options);
    } catch (const FitError& e) {
        throw FitError(std::string("ball-bar, second sphere: ") + e.what());
    }
    bar.distance = (to_eigen(bar.first.centre) - to_eigen(bar.second.centre)).norm();
    bar.message = "ball-bar: centre distance " + number(bar.distance, 4) + " mm, diameters " +
                  number(2 * bar.first.radius, 4) + " and " + number(2 * bar.second.radius, 4) +
                  " mm; RMS " + number(bar.first.fit.rms, 4) + " and " +
                  number(bar.second.fit.rms, 4) + " mm";
    return bar;
}

BallBarFit fit_ball_bar(std::span<const Vec3> points, const FitOptions& options,
                        std::vector<std::uint8_t>* cluster) {
    const Conditioned c = condition(points, "ball-bar", 8);
    const Principal pca = principal_axes(c.q);
    // 2-means, started at the two extreme points along the principal direction.
    std::size_t lo = 0, hi = 0;
    for (std::size_t i = 0; i < c.q.size(); ++i) {
        const double t = c.q[i].dot(pca.directions.col(0));
        if (t < c.q[lo].dot(pca.directions.col(0)))
            lo = i;
        if (t > c.q[hi].dot(pca.directions.col(0)))
            hi = i;
    }
    std::array<Vector3d, 2> centre = {c.q[lo], c.q[hi]};
    std::vector<std::uint8_t> label(c.q.size(), 0);
    for (int it = 0; it < 100; ++it) {
        bool changed = it == 0;
        std::array<Vector3d, 2> sum = {Vector3d::Zero(), Vector3d::Zero()};
        std::array<std::size_t, 2> count = {0, 0};
        for (std::size_t i = 0; i < c.q.size(); ++i) {
            const std::uint8_t l =
                (c.q[i] - centre[1]).squaredNorm() < (c.q[i] - centre[0]).squaredNorm() ? 1 : 0;
            changed = changed || l != label[i];
            label[i] = l;
            sum[l] += c.q[i];
            ++count[l];
        }
        if (count[0] == 0 || count[1] == 0)
            break;
        centre = {sum[0] / static_cast<double>(count[0]), sum[1] / static_cast<double>(count[1])};
        if (!changed)
            break;
    }
    std::array<std::vector<Vec3>, 2> parts;
    for (std::size_t i = 0; i < points.size(); ++i)
        parts[label[i]].push_back(points[i]);
    if (cluster)
        *cluster = label;
    return fit_ball_bar(parts[0], parts[1], options);
}

// ---------------------------------------------------------------- k-d tree

namespace {
constexpr std::uint32_t kLeafSize = 8;
}

PointIndex::PointIndex(std::span<const Vec3> points) : points_(points.begin(), points.end()) {
    order_.reserve(points_.size());
    for (std::size_t i = 0; i < points_.size(); ++i)
        order_.push_back(static_cast<std::uint32_t>(i));
    if (!points_.empty())
        build(0, static_cast<std::uint32_t>(points_.size()));
}

std::int32_t PointIndex::build(std::uint32_t begin, std::uint32_t end) {
    const auto id = static_cast<std::int32_t>(nodes_.size());
    nodes_.push_back(Node{begin, end});
    if (end - begin <= kLeafSize)
        return id;
    Vec3 lo = points_[order_[begin]], hi = lo;
    for (std::uint32_t i = begin; i < end; ++i)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], points_[order_[i]][a]);
            hi[a] = std::max(hi[a], points_[order_[i]][a]);
        }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (hi[a] - lo[a] > hi[axis] - lo[axis])
            axis = a;
    const std::uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(
        order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
        [&](std::uint32_t x, std::uint32_t y) { return points_[x][axis] < points_[y][axis]; });
    nodes_[static_cast<std::size_t>(id)].axis = static_cast<std::uint8_t>(axis);
    nodes_[static_cast<std::size_t>(id)].split = points_[order_[mid]][axis];
    const std::int32_t left = build(begin, mid);
    const std::int32_t right = build(mid, end);
    nodes_[static_cast<std::size_t>(id)].left = left;
    nodes_[static_cast<std::size_t>(id)].right = right;
    return id;
}

namespace {
double squared_distance(const Vec3& a, const Vec3& b) {
    const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return dx * dx + dy * dy + dz * dz;
}
} // namespace

void PointIndex::search_nearest(std::int32_t node, const Vec3& q, double& best,
                                std::size_t& index) const {
    const Node& n = nodes_[static_cast<std::size_t>(node)];
    if (n.left < 0) {
        for (std::uint32_t i = n.begin; i < n.end; ++i) {
            const double d = squared_distance(points_[order_[i]], q);
            if (d < best) {
                best = d;
                index = order_[i];
            }
        }
        return;
    }
    const double diff = q[n.axis] - n.split;
    search_nearest(diff < 0 ? n.left : n.right, q, best, index);
    if (diff * diff < best)
        search_nearest(diff < 0 ? n.right : n.left, q, best, index);
}

std::size_t PointIndex::nearest(const Vec3& query, double* squared) const {
    double best = std::numeric_limits<double>::infinity();
    std::size_t index = points_.size();
    if (!points_.empty())
        search_nearest(0, query, best, index);
    if (squared)
        *squared = best;
    return index;
}

void PointIndex::search_k(std::int32_t node, const Vec3& q, std::size_t k,
                          std::vector<std::pair<double, std::size_t>>& heap) const {
    const Node& n = nodes_[static_cast<std::size_t>(node)];
    if (n.left < 0) {
        for (std::uint32_t i = n.begin; i < n.end; ++i) {
            const double d = squared_distance(points_[order_[i]], q);
            if (heap.size() < k) {
                heap.emplace_back(d, order_[i]);
                std::push_heap(heap.begin(), heap.end());
            } else if (d < heap.front().first) {
                std::pop_heap(heap.begin(), heap.end());
                heap.back() = {d, order_[i]};
                std::push_heap(heap.begin(), heap.end());
            }
        }
        return;
    }
    const double diff = q[n.axis] - n.split;
    search_k(diff < 0 ? n.left : n.right, q, k, heap);
    if (heap.size() < k || diff * diff < heap.front().first)
        search_k(diff < 0 ? n.right : n.left, q, k, heap);
}

void PointIndex::nearest_k(const Vec3& query, std::size_t k,
                           std::vector<std::pair<double, std::size_t>>& out) const {
    out.clear();
    if (points_.empty() || k == 0)
        return;
    search_k(0, query, k, out);
    std::sort_heap(out.begin(), out.end());
}

} // namespace fpp::calib
