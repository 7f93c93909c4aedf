// The calibration's uncertainty carried to lengths (see trueness.hpp and
// trueness_prediction.hpp).

#include "trueness_prediction.hpp"

#include "calibration_covariance.hpp"
#include "fpp/calib/stereo_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace fpp::calib {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Where the ray of camera pixel `pixel` meets projector column `column`,
// starting the search at depth z0 (mm): secant steps on the column's error
// along the ray. False when there is no ray or the search does not settle.
bool triangulate_column(const StereoCalibration& c, const Vec2& pixel, double column, double z0,
                        Vec3& point) {
    Vec2 n{};
    if (!c.camera_ray(pixel, n))
        return false;
    const auto error = [&](double z) {
        return c.projector_pixel({n[0] * z, n[1] * z, z})[0] - column;
    };
    double za = z0, zb = z0 * 1.001;
    double ea = error(za), eb = error(zb);
    for (int it = 0; it < 50; ++it) {
        if (!std::isfinite(ea) || !std::isfinite(eb) || eb == ea)
            return false;
        const double zc = zb - eb * (zb - za) / (eb - ea);
        za = zb;
        ea = eb;
        zb = zc;
        eb = error(zb);
        if (std::fabs(zb - za) < 1e-10 * std::fabs(zb)) {
            if (!(zb > 0))
                return false;
            point = {n[0] * zb, n[1] * zb, zb};
            return true;
        }
    }
    return false;
}

double distance(const Vec3& a, const Vec3& b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                     (a[2] - b[2]) * (a[2] - b[2]));
}

// A length as the scanner sees it: its two ends' camera pixels and
// projector columns (through the calibration it is predicted for), and
// their true depths (where the searches start).
struct SeenLength {
    Vec2 pixel[2];
    double column[2];
    double depth[2];
};

SeenLength see(const StereoCalibration& truth, const Vec3& a, const Vec3& b) {
    SeenLength s{};
    const Vec3 ends[2] = {a, b};
    for (int k = 0; k < 2; ++k) {
        s.pixel[k] = truth.camera_pixel(ends[k]);
        s.column[k] = truth.projector_pixel(ends[k])[0];
        s.depth[k] = ends[k][2];
    }
    return s;
}

double measure(const StereoCalibration& c, const SeenLength& s) {
    Vec3 ends[2];
    for (int k = 0; k < 2; ++k)
        if (!triangulate_column(c, s.pixel[k], s.column[k], s.depth[k], ends[k]))
            return kNaN;
    return distance(ends[0], ends[1]);
}

std::string mm_text(double v) {
    std::ostringstream o;
    o << std::fixed << std::setprecision(v < 0.0995 ? 3 : 2) << v;
    return o.str();
}

} // namespace

double measured_length(const StereoCalibration& truth, const StereoCalibration& measure_with,
                       const Vec3& a, const Vec3& b) {
    return measure(measure_with, see(truth, a, b));
}

std::string trueness_summary(const Trueness& t) {
    if (!t.known())
        return "Predicted trueness: unknown (not computed for this calibration).\n";
    std::ostringstream o;
    const auto ppm = [&](double sigma) {
        return std::to_string(static_cast<long>(std::lround(sigma / t.length_mm * 1e6)));
    };
    const LengthSigma& m = t.middle();
    o << "Predicted trueness (1 sigma, from the calibration's own uncertainty): a "
      << std::lround(t.length_mm) << " mm length at " << std::lround(m.depth_mm)
      << " mm is true to +-" << mm_text(m.along_depth_mm) << " mm along depth ("
      << ppm(m.along_depth_mm) << " ppm) and +-" << mm_text(m.across_mm) << " mm across ("
      << ppm(m.across_mm) << " ppm); along depth +-" << mm_text(t.at[0].along_depth_mm) << " mm at "
      << std::lround(t.at[0].depth_mm) << " mm and +-" << mm_text(t.at[2].along_depth_mm)
      << " mm at " << std::lround(t.at[2].depth_mm) << " mm.\n";
    return o.str();
}

namespace detail {

SessionDepths session_depths(const RigState& s, const std::vector<CornerObservation>& corners,
                             const std::vector<bool>& pose_used) {
    std::vector<double> z;
    for (const CornerObservation& o : corners) {
        if (!pose_used[std::size_t(o.pose)])
            continue;
        const RigidPose& p = s.poses[std::size_t(o.pose)];
        z.push_back(p.R[6] * o.board[0] + p.R[7] * o.board[1] + p.R[8] * o.board[2] + p.t[2]);
    }
    SessionDepths d;
    if (z.empty())
        return d;
    std::sort(z.begin(), z.end());
    const auto at = [&](double q) { return z[std::size_t(q * double(z.size() - 1) + 0.5)]; };
    d.near_mm = at(0.1);
    d.middle_mm = at(0.5);
    d.far_mm = at(0.9);
    return d;
}

Trueness predict_trueness(const TruenessInputs& in, TruenessMap* map) {
    const RigState& s = *in.state;
    const Eigen::MatrixXd& cov = *in.covariance;
    const double half = in.length_mm / 2;
    const StereoCalibration base = calibration_of(s, in.camera_size);

    // The lengths: along depth and across at the three depths, then one
    // along each map cell's ray at the middle depth.
    std::vector<SeenLength> lengths;
    const double depths[3] = {in.depths.near_mm, in.depths.middle_mm, in.depths.far_mm};
    for (double z : depths) {
        lengths.push_back(see(base, {0, 0, z - half}, {0, 0, z + half}));
        lengths.push_back(see(base, {-half, 0, z}, {half, 0, z}));
    }
    int cells_x = 0, cells_y = 0, cell = 0;
    std::vector<bool> has_ray;
    if (map) {
        cell = std::max(1, std::max(in.camera_size.width, in.camera_size.height) /
                               std::max(1, in.map_cells_across));
        cells_x = (in.camera_size.width + cell - 1) / cell;
        cells_y = (in.camera_size.height + cell - 1) / cell;
        for (int y = 0; y < cells_y; ++y)
            for (int x = 0; x < cells_x; ++x) {
                const Vec2 pixel{std::min(x * cell + cell / 2.0, in.camera_size.width - 1.0),
                                 std::min(y * cell + cell / 2.0, in.camera_size.height - 1.0)};
                Vec2 n{};
                const bool ok = base.camera_ray(pixel, n);
                has_ray.push_back(ok);
                const double norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + 1);
                const Vec3 dir{n[0] / norm, n[1] / norm, 1 / norm};
                const double r = in.depths.middle_mm * norm; // along the ray to the middle depth
                lengths.push_back(
                    see(base, {dir[0] * (r - half), dir[1] * (r - half), dir[2] * (r - half)},
                        {dir[0] * (r + half), dir[1] * (r + half), dir[2] * (r + half)}));
            }
    }

    // Sensitivity of every length to each parameter with a variance.
    std::vector<Eigen::Index> free;
    for (Eigen::Index k = 0; k < cov.rows(); ++k)
        if (cov(k, k) > 0)
            free.push_back(k);
    const Eigen::Index m = Eigen::Index(lengths.size()), n = Eigen::Index(free.size());
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(m, n);
    const FreeParameters all = calibration_parameters();
    std::vector<double> step(std::size_t(cov.rows()), 0.0);
    const auto lengths_at = [&](Eigen::Index k, double h, Eigen::VectorXd& out) {
        RigState t = s;
        step.assign(step.size(), 0.0);
        step[std::size_t(k)] = h;
        apply_increment(t, {}, all, step);
        const StereoCalibration c = calibration_of(t, in.camera_size);
        out.resize(m);
        for (Eigen::Index j = 0; j < m; ++j)
            out(j) = measure(c, lengths[std::size_t(j)]);
    };
    Eigen::VectorXd plus, minus;
    for (Eigen::Index i = 0; i < n; ++i) {
        const Eigen::Index k = free[std::size_t(i)];
        const double h = 0.1 * std::sqrt(cov(k, k));
        lengths_at(k, h, plus);
        lengths_at(k, -h, minus);
        G.col(i) = (plus - minus) / (2 * h);
    }
    Eigen::MatrixXd sub(n, n);
    for (Eigen::Index a = 0; a < n; ++a)
        for (Eigen::Index b = 0; b < n; ++b)
            sub(a, b) = cov(free[std::size_t(a)], free[std::size_t(b)]);
    const Eigen::MatrixXd GS = G * sub;
    const auto sigma = [&](Eigen::Index j) {
        const double v = GS.row(j).dot(G.row(j));
        return std::isfinite(v) ? std::sqrt(std::max(v, 0.0)) : kNaN;
    };

    if (in.middle_depth_gradient) {
        *in.middle_depth_gradient = Eigen::VectorXd::Zero(cov.rows());
        for (Eigen::Index i = 0; i < n; ++i)
            (*in.middle_depth_gradient)(free[std::size_t(i)]) = G(2, i); // middle, along depth
    }
    Trueness t;
    t.length_mm = in.length_mm;
    for (int d = 0; d < 3; ++d) {
        t.at[std::size_t(d)].depth_mm = depths[d];
        t.at[std::size_t(d)].along_depth_mm = sigma(2 * d);
        t.at[std::size_t(d)].across_mm = sigma(2 * d + 1);
    }
    if (map) {
        map->cell_px = cell;
        map->depth_mm = in.depths.middle_mm;
        map->length_mm = in.length_mm;
        map->sigma_mm =
            Image<float>(Size{cells_x, cells_y}, 1, std::numeric_limits<float>::quiet_NaN());
        for (int k = 0; k < cells_x * cells_y; ++k)
            if (has_ray[std::size_t(k)])
                map->sigma_mm.data()[k] = static_cast<float>(sigma(6 + k));
    }
    return t;
}

} // namespace detail
} // namespace fpp::calib
