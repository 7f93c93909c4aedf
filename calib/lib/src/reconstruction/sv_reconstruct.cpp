// Stereo-vision reconstruction with lens distortion compensated (see
// fpp/calib/sv_reconstruct.hpp).

#include "fpp/calib/sv_reconstruct.hpp"

#include "fpp/enum_names.hpp"
#include "fpp/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace fpp::calib {

constexpr EnumName<ReconstructAxes> kReconstructAxesNames[] = {
    {ReconstructAxes::automatic, "auto"},
    {ReconstructAxes::x, "x"},
    {ReconstructAxes::xy, "xy"},
};

ReconstructAxes parse_axes(const std::string& name) {
    return parse_name(kReconstructAxesNames, "axes", name);
}

const char* to_string(ReconstructAxes axes) {
    return name_of(kReconstructAxesNames, axes);
}

ReconstructAxes resolve_axes(const DecodeResult& decoded, ReconstructAxes requested) {
    const bool has_x = !decoded.proj_x.empty();
    const bool has_y = !decoded.proj_y.empty();
    if (!has_x)
        throw std::invalid_argument(
            "the capture decodes no projector column (no phase along x): SV reconstruction "
            "needs x");
    if (requested == ReconstructAxes::automatic)
        return has_y ? ReconstructAxes::xy : ReconstructAxes::x;
    if (requested == ReconstructAxes::xy && !has_y)
        throw std::invalid_argument(
            "--axes xy needs the projector row, but the capture decodes no phase along y");
    return requested;
}

namespace {

// The calibrated 5-coefficient part of fpp::LensModel (fpp/lens_model.hpp),
// inlined here because it runs several times per pixel: normalised
// undistorted (x, y) -> normalised distorted (xd, yd) and its Jacobian
// [dxd/dx dxd/dy; dyd/dx dyd/dy]. Simulated lenses with terms outside that
// model go through LensModel itself.
struct Distortion {
    LensModel lens;
    bool extra; // terms outside the calibrated model (simulated lenses only)
    explicit Distortion(const LensModel& l) : lens(l), extra(l.has_unmodelled_terms()) {}

    void apply(double x, double y, double& xd, double& yd, double* J) const {
        if (extra) {
            const Vec2 d = lens.distort({x, y});
            xd = d[0];
            yd = d[1];
            if (J) {
                const Mat2 m = lens.distortion_jacobian({x, y});
                for (int i = 0; i < 4; ++i)
                    J[i] = m[std::size_t(i)];
            }
            return;
        }
        const double k1 = lens.k1, k2 = lens.k2, k3 = lens.k3, p1 = lens.p1, p2 = lens.p2;
        const double r2 = x * x + y * y;
        const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
        xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
        yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
        if (J) {
            const double dradial = k1 + r2 * (2 * k2 + r2 * 3 * k3);
            const double cross = 2 * x * y * dradial + 2 * p1 * x + 2 * p2 * y;
            J[0] = radial + 2 * x * x * dradial + 2 * p1 * y + 6 * p2 * x;
            J[1] = cross;
            J[2] = cross;
            J[3] = radial + 2 * y * y * dradial + 6 * p1 * y + 2 * p2 * x;
        }
    }
};

enum class Outcome { point, rejected, outside_projector, not_converged };

// Everything the per-pixel solvers need, in plain doubles.
struct Geometry {
    LensModel projector;
    Distortion dist;
    const CorrectionGrid* correction;  // the projector's, empty when none
    double R[9];                       // camera -> projector rotation
    double T[3];                       // mm
    double Rt[9];                      // projector -> camera rotation
    double C[3];                       // projector centre in the camera frame, mm
    double u_min, u_max, v_min, v_max; // accepted projector coordinates
    double tolerance_px;
    int max_iterations;
    XOnlySolver solver;
    double max_gap_mm;

    Geometry(const StereoCalibration& c, const SvOptions& o)
        : projector(c.projector), dist(c.projector), correction(&c.projector_correction),
          tolerance_px(o.tolerance_px), max_iterations(o.max_iterations), solver(o.solver),
          max_gap_mm(o.max_ray_gap_mm) {
        const Mat3 rt = transpose(c.R);
        const Vec3 centre = c.projector_centre();
        for (int i = 0; i < 9; ++i) {
            R[i] = c.R[std::size_t(i)];
            Rt[i] = rt[std::size_t(i)];
        }
        for (int i = 0; i < 3; ++i) {
            T[i] = c.T[std::size_t(i)];
            C[i] = centre[std::size_t(i)];
        }
        const double m = o.projector_margin_px;
        if (m < 0) {
            u_min = v_min = -std::numeric_limits<double>::infinity();
            u_max = v_max = std::numeric_limits<double>::infinity();
        } else {
            u_min = -0.5 - m;
            v_min = -0.5 - m;
            u_max = c.projector_size.width - 0.5 + m;
            v_max = c.projector_size.height - 0.5 + m;
        }
    }

    // Projector column of the normalised undistorted point (w, y) and its
    // row (projector px, correction included); optionally d(column)/dw along
    // y = a + b w.
    double column(double w, double y, double b, double& row, double* dcol_dw) const {
        double xd, yd;
        double J[4];
        dist.apply(w, y, xd, yd, dcol_dw ? J : nullptr);
        const double u = projector.fu * xd + projector.skew * yd + projector.cu;
        const double v = projector.fv * yd + projector.cv;
        double du_dw = 0;
        if (dcol_dw)
            du_dw = projector.fu * (J[0] + J[1] * b) + projector.skew * (J[2] + J[3] * b);
        if (correction->empty()) {
            row = v;
            if (dcol_dw)
                *dcol_dw = du_dw;
            return u;
        }
        Vec2 d{};
        if (dcol_dw) {
            Mat2 G{};
            correction->displacement_and_jacobian({u, v}, d, G);
            const double dv_dw = projector.fv * (J[2] + J[3] * b);
            *dcol_dw = (1 + G[0]) * du_dw + G[1] * dv_dw;
        } else {
            d = correction->displacement({u, v});
        }
        row = v + d[1];
        return u + d[0];
    }

    // x only: camera ray (xn, yn, 1), projector column xp.
    Outcome solve_x(double xn, double yn, double xp, double out[3], int& iterations) const {
        iterations = 0;
        if (!(xp >= u_min && xp <= u_max))
            return Outcome::outside_projector;
        // Ray direction in the projector frame; the ray's points are s q + T.
        const double qx = R[0] * xn + R[1] * yn + R[2];
        const double qy = R[3] * xn + R[4] * yn + R[5];
        const double qz = R[6] * xn + R[7] * yn + R[8];
        // Its image in the projector's normalised plane: the line l = q x T,
        // l0 x + l1 y + l2 = 0, i.e. y = a + b x.
        const double l0 = qy * T[2] - qz * T[1];
        const double l1 = qz * T[0] - qx * T[2];
        const double l2 = qx * T[1] - qy * T[0];
        if (!(std::fabs(l1) > 1e-12 * (std::fabs(l0) + std::fabs(l1))))
            return Outcome::rejected; // epipolar line along a projector column: no depth from x
        const double a = -l2 / l1, b = -l0 / l1;

        const LensModel& p = projector;
        // Start: the distortion-free plane of column xp.
        double w = (xp - p.cu - p.skew * a) / (p.fu + p.skew * b);
        double row = 0;
        bool converged = false;
        if (solver == XOnlySolver::newton) {
            for (int it = 0;; ++it) {
                double slope = 0;
                const double g = column(w, a + b * w, b, row, &slope) - xp;
                if (std::fabs(g) <= tolerance_px) {
                    // A root where the column does not grow with w lies in a
                    // folded part of the distortion (outside the lens's field).
                    converged = slope > 0;
                    iterations = it;
                    break;
                }
                if (it >= max_iterations || !(std::fabs(slope) > 0) || !std::isfinite(g)) {
                    iterations = it;
                    break;
                }
                w -= g / slope;
            }
        } else {
            // The paper's iteration: project the guess, undistort (xp, its
            // distorted row) to get the plane of constant undistorted x, intersect.
            for (int it = 0;; ++it) {
                const double g = column(w, a + b * w, b, row, nullptr) - xp;
                if (std::fabs(g) <= tolerance_px) {
                    converged = true;
                    iterations = it;
                    break;
                }
                Vec2 n{}, model{};
                if (it >= max_iterations || !std::isfinite(g) ||
                    !correction->remove({xp, row}, model) || !p.pixel_to_normalised(model, n)) {
                    iterations = it;
                    break;
                }
                w = n[0];
            }
        }
        if (!converged)
            return Outcome::not_converged;
        if (!(row >= v_min && row <= v_max))
            return Outcome::outside_projector;
        // Depth along the camera ray: (s qx + Tx) / (s qz + Tz) = w.
        const double s = (w * T[2] - T[0]) / (qx - w * qz);
        if (!(s > 0) || !std::isfinite(s) || !(s * qz + T[2] > 0))
            return Outcome::rejected;
        out[0] = s * xn;
        out[1] = s * yn;
        out[2] = s;
        return Outcome::point;
    }

    // Projector pixel -> normalised undistorted coordinates: Newton from the
    // distorted coordinates (the projector's distortion is mild: 2 or 3
    // steps to a residual of 1e-13, ~1e-10 px), with LensModel's safeguarded
    // solver as the fallback.
    bool undistort_projector(double up, double vp, double& xn, double& yn) const {
        if (!correction->empty()) {
            Vec2 model{};
            if (!correction->remove({up, vp}, model))
                return false;
            up = model[0];
            vp = model[1];
        }
        const LensModel& p = projector;
        const double yd = (vp - p.cv) / p.fv;
        const double xd = (up - p.cu - p.skew * yd) / p.fu;
        double x = xd, y = yd;
        for (int it = 0; it < 8; ++it) {
            double fx, fy, J[4];
            dist.apply(x, y, fx, fy, J);
            fx -= xd;
            fy -= yd;
            const double det = J[0] * J[3] - J[1] * J[2];
            if (!(det > 0) || !(J[0] > 0) || !(J[3] > 0))
                break; // folded: let LensModel decide
            if (std::fabs(fx) + std::fabs(fy) <= 1e-13) {
                xn = x;
                yn = y;
                return true;
            }
            x -= (J[3] * fx - J[1] * fy) / det;
            y -= (J[0] * fy - J[2] * fx) / det;
        }
        Vec2 n{};
        if (!p.undistort({xd, yd}, n))
            return false;
        xn = n[0];
        yn = n[1];
        return true;
    }

    // x and y: midpoint of the common perpendicular of the two rays.
    Outcome solve_xy(double xn, double yn, double up, double vp, double out[3], double& gap) const {
        if (!(up >= u_min && up <= u_max && vp >= v_min && vp <= v_max))
            return Outcome::outside_projector;
        double pxn, pyn;
        if (!undistort_projector(up, vp, pxn, pyn))
            return Outcome::rejected;
        // Camera ray s d1 (origin 0); projector ray C + t d2, in the camera frame.
        const double d1[3] = {xn, yn, 1.0};
        const double d2[3] = {Rt[0] * pxn + Rt[1] * pyn + Rt[2], Rt[3] * pxn + Rt[4] * pyn + Rt[5],
                              Rt[6] * pxn + Rt[7] * pyn + Rt[8]};
        const double a11 = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2];
        const double a12 = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2];
        const double a22 = d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2];
        const double b1 = d1[0] * C[0] + d1[1] * C[1] + d1[2] * C[2];
        const double b2 = d2[0] * C[0] + d2[1] * C[1] + d2[2] * C[2];
        const double det = a11 * a22 - a12 * a12;
        if (!(det > 1e-12 * a11 * a22))
            return Outcome::rejected; // parallel rays
        // Minimise |s d1 - C - t d2|^2.
        const double s = (b1 * a22 - a12 * b2) / det;
        const double t = (a12 * b1 - a11 * b2) / det;
        if (!(s > 0) || !(t > 0))
            return Outcome::rejected;
        const double p1[3] = {s * d1[0], s * d1[1], s * d1[2]};
        const double p2[3] = {C[0] + t * d2[0], C[1] + t * d2[1], C[2] + t * d2[2]};
        gap = std::sqrt((p1[0] - p2[0]) * (p1[0] - p2[0]) + (p1[1] - p2[1]) * (p1[1] - p2[1]) +
                        (p1[2] - p2[2]) * (p1[2] - p2[2]));
        if (!(gap <= max_gap_mm))
            return Outcome::rejected;
        for (int i = 0; i < 3; ++i)
            out[i] = 0.5 * (p1[i] + p2[i]);
        return Outcome::point;
    }
};

// Per-worker tallies, padded so that workers do not share cache lines.
struct alignas(64) Tally {
    std::size_t decoded = 0, points = 0, not_converged = 0, rejected = 0, outside = 0;
    std::size_t iterations = 0;
    int max_iterations = 0;
    double gap_sq = 0, gap_max = 0;
};

} // namespace

SvReconstructor::SvReconstructor(const StereoCalibration& calibration, const SvOptions& options)
    : calibration_(calibration), options_(options),
      pool_(std::make_unique<ThreadPool>(options.threads)) {
    if (!calibration_.sizes_known())
        throw std::invalid_argument("SV reconstruction: the calibration's image sizes are unknown");
    for (const LensModel* l : {&calibration_.camera, &calibration_.projector})
        if (!(l->fu > 0) || !(l->fv > 0))
            throw std::invalid_argument("SV reconstruction: non-positive focal length");
    if (!(options_.tolerance_px > 0) || options_.max_iterations < 1)
        throw std::invalid_argument("SV reconstruction: tolerance must be > 0, iterations >= 1");

    // Camera rays once per calibration: LensModel's inverse, computed by
    // Newton from the previous pixel's solution (2 or 3 steps instead of ~6
    // from the distorted point: the camera's distortion can be strong),
    // with the same fold checks; LensModel::pixel_to_normalised wherever that
    // does not converge.
    const Size size = calibration_.camera_size;
    rays_ = Image<float>(size, 2);
    const LensModel camera = calibration_.camera;
    const CorrectionGrid& correction = calibration_.camera_correction;
    const Distortion dist(camera);
    float* rays = rays_.data();
    pool_->parallel_for(size.height, 4, [&](int begin, int end, int) {
        constexpr float nan = std::numeric_limits<float>::quiet_NaN();
        for (int v = begin; v < end; ++v) {
            float* out = rays + std::size_t(v) * std::size_t(size.width) * 2;
            bool have_previous = false;
            double x = 0, y = 0;
            for (int u = 0; u < size.width; ++u) {
                Vec2 model{double(u), double(v)};
                if (!correction.remove({double(u), double(v)}, model)) {
                    have_previous = false;
                    out[2 * u] = out[2 * u + 1] = nan;
                    continue;
                }
                const Vec2 d = camera.pixel_to_distorted(model);
                if (!have_previous) {
                    x = d[0];
                    y = d[1];
                }
                bool ok = false;
                for (int it = 0; it < 10; ++it) {
                    double fx, fy, J[4];
                    dist.apply(x, y, fx, fy, J);
                    fx -= d[0];
                    fy -= d[1];
                    const double det = J[0] * J[3] - J[1] * J[2];
                    if (!(det > 0) || !(J[0] > 0) || !(J[3] > 0))
                        break; // folded
                    if (std::fabs(fx) + std::fabs(fy) <= 1e-14) {
                        ok = true;
                        break;
                    }
                    x -= (J[3] * fx - J[1] * fy) / det;
                    y -= (J[0] * fy - J[2] * fx) / det;
                }
                if (!ok) {
                    Vec2 n{};
                    ok = camera.pixel_to_normalised(model, n);
                    x = n[0];
                    y = n[1];
                }
                have_previous = ok;
                out[2 * u] = ok ? static_cast<float>(x) : nan;
                out[2 * u + 1] = ok ? static_cast<float>(y) : nan;
            }
        }
    });
}

SvReconstructor::~SvReconstructor() = default;
SvReconstructor::SvReconstructor(SvReconstructor&&) noexcept = default;
SvReconstructor& SvReconstructor::operator=(SvReconstructor&&) noexcept = default;

bool SvReconstructor::triangulate_x(double u, double v, double proj_x, Vec3& point,
                                    int* iterations) const {
    Vec2 n{};
    int it = 0;
    bool ok = false;
    if (calibration_.camera_ray({u, v}, n)) {
        const Geometry g(calibration_, options_);
        ok = g.solve_x(n[0], n[1], proj_x, point.data(), it) == Outcome::point;
    }
    if (iterations)
        *iterations = it;
    return ok;
}

bool SvReconstructor::triangulate_xy(double u, double v, double proj_x, double proj_y, Vec3& point,
                                     double* ray_gap_mm) const {
    Vec2 n{};
    double gap = 0;
    bool ok = false;
    if (calibration_.camera_ray({u, v}, n)) {
        const Geometry g(calibration_, options_);
        ok = g.solve_xy(n[0], n[1], proj_x, proj_y, point.data(), gap) == Outcome::point;
    }
    if (ray_gap_mm)
        *ray_gap_mm = gap;
    return ok;
}

bool SvReconstructor::triangulate_pixel_x(int u, int v, double proj_x, Vec3& point) const {
    if (u < 0 || v < 0 || u >= rays_.width() || v >= rays_.height())
        throw std::invalid_argument("SV reconstruction: pixel outside the camera image");
    const double xn = double(rays_.at(u, v, 0)), yn = double(rays_.at(u, v, 1));
    if (!std::isfinite(xn) || !std::isfinite(yn))
        return false;
    int iterations = 0;
    return Geometry(calibration_, options_).solve_x(xn, yn, proj_x, point.data(), iterations) ==
           Outcome::point;
}

SvStats SvReconstructor::reconstruct(const DecodeResult& decoded, ReconstructAxes requested,
                                     PointCloud& cloud) const {
    const Size size = calibration_.camera_size;
    if (decoded.proj_x.size() != size || (!decoded.proj_y.empty() && decoded.proj_y.size() != size))
        throw std::invalid_argument(
            "SV reconstruction: the decoded images are not of the calibration's camera size");
    const ReconstructAxes axes = resolve_axes(decoded, requested);
    const bool use_y = axes == ReconstructAxes::xy;

    if (cloud.xyz.size() != size || cloud.xyz.channels() != 3)
        cloud.xyz = Image<float>(size, 3);
    if (cloud.quality.size() != size || cloud.quality.channels() != 1)
        cloud.quality = Image<float>(size, 1);
    if (cloud.intensity.size() != size || cloud.intensity.channels() != 1)
        cloud.intensity = Image<float>(size, 1);

    const Geometry geometry(calibration_, options_);
    std::vector<Tally> tallies(std::size_t(pool_->size()));
    const float* px = decoded.proj_x.data();
    const float* py = use_y ? decoded.proj_y.data() : nullptr;
    const float* modulation =
        decoded.modulation.size() == size ? decoded.modulation.data() : nullptr;
    const float* mean = decoded.mean.size() == size ? decoded.mean.data() : nullptr;
    const float* rays = rays_.data();
    float* xyz = cloud.xyz.data();
    float* quality = cloud.quality.data();
    float* intensity = cloud.intensity.data();
    const std::size_t width = std::size_t(size.width);

    pool_->parallel_for(size.height, 8, [&](int begin, int end, int worker) {
        constexpr float nan = std::numeric_limits<float>::quiet_NaN();
        Tally& tally = tallies[std::size_t(worker)];
        for (std::size_t i = std::size_t(begin) * width, last = std::size_t(end) * width; i < last;
             ++i) {
            float* out = xyz + 3 * i;
            out[0] = out[1] = out[2] = nan;
            quality[i] = nan;
            intensity[i] = nan;
            const float x = px[i];
            const float y = py ? py[i] : 0.0f;
            if (!std::isfinite(x) || !std::isfinite(y))
                continue;
            ++tally.decoded;
            const double xn = double(rays[2 * i]), yn = double(rays[2 * i + 1]);
            double point[3];
            Outcome outcome = Outcome::rejected;
            if (std::isfinite(xn)) {
                if (py) {
                    double gap = 0;
                    outcome = geometry.solve_xy(xn, yn, double(x), double(y), point, gap);
                    if (outcome == Outcome::point) {
                        tally.gap_sq += gap * gap;
                        tally.gap_max = std::max(tally.gap_max, gap);
                    }
                } else {
                    int iterations = 0;
                    outcome = geometry.solve_x(xn, yn, double(x), point, iterations);
                    if (outcome == Outcome::point) {
                        tally.iterations += std::size_t(iterations);
                        tally.max_iterations = std::max(tally.max_iterations, iterations);
                    }
                }
            }
            if (outcome == Outcome::rejected) {
                ++tally.rejected;
                continue;
            }
            if (outcome == Outcome::outside_projector) {
                ++tally.outside;
                continue;
            }
            if (outcome == Outcome::not_converged) {
                ++tally.not_converged;
                continue;
            }
            ++tally.points;
            out[0] = static_cast<float>(point[0]);
            out[1] = static_cast<float>(point[1]);
            out[2] = static_cast<float>(point[2]);
            quality[i] = modulation ? modulation[i] : nan;
            intensity[i] = mean ? mean[i] : nan;
        }
    });

    SvStats stats;
    stats.axes = axes;
    double gap_sq = 0;
    for (const Tally& t : tallies) {
        stats.decoded += t.decoded;
        stats.points += t.points;
        stats.not_converged += t.not_converged;
        stats.rejected += t.rejected;
        stats.outside_projector += t.outside;
        stats.iterations += t.iterations;
        stats.max_iterations = std::max(stats.max_iterations, t.max_iterations);
        gap_sq += t.gap_sq;
        stats.max_ray_gap_mm = std::max(stats.max_ray_gap_mm, t.gap_max);
    }
    if (use_y && stats.points > 0)
        stats.rms_ray_gap_mm = std::sqrt(gap_sq / double(stats.points));
    return stats;
}

} // namespace fpp::calib
