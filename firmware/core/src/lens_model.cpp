#include "fpp/lens_model.hpp"

#include <cmath>

namespace fpp {

bool LensModel::has_unmodelled_terms() const {
    return k4 != 0 || s1 != 0 || s2 != 0 || s3 != 0 || s4 != 0 || t1 != 0 || t2 != 0 ||
           dc_k1 != 0 || dc_k2 != 0;
}

void LensModel::drop_unmodelled_terms() {
    k4 = s1 = s2 = s3 = s4 = t1 = t2 = 0;
    dc_k1 = dc_k2 = dc_x = dc_y = 0;
}

namespace {

// The decentred element's radial profile g(rho2) = dc_k1 rho2 + dc_k2 rho2^2.
double decentred_profile(const LensModel& l, double rho2) {
    return rho2 * (l.dc_k1 + l.dc_k2 * rho2);
}

// Its displacement at normalised (x, y), minus the one at the axis (0, 0).
Vec2 decentred_displacement(const LensModel& l, double x, double y) {
    if (l.dc_k1 == 0 && l.dc_k2 == 0)
        return {0, 0};
    const double dx = x - l.dc_x, dy = y - l.dc_y;
    const double g = decentred_profile(l, dx * dx + dy * dy);
    const double g_axis = decentred_profile(l, l.dc_x * l.dc_x + l.dc_y * l.dc_y);
    return {dx * g + l.dc_x * g_axis, dy * g + l.dc_y * g_axis};
}

} // namespace

Vec2 LensModel::distort(Vec2 n) const {
    const double x = n[0], y = n[1];
    const double r2 = x * x + y * y;
    const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * (k3 + r2 * k4)));
    const double d2 = x * x - y * y;
    const double xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) + r2 * (s1 + s2 * r2) +
                      t1 * d2 + 2 * t2 * x * y;
    const double yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y + r2 * (s3 + s4 * r2) +
                      t2 * d2 - 2 * t1 * x * y;
    const Vec2 decentred = decentred_displacement(*this, x, y);
    return {xd + decentred[0], yd + decentred[1]};
}

Mat2 LensModel::distortion_jacobian(Vec2 n) const {
    const double x = n[0], y = n[1];
    const double r2 = x * x + y * y;
    const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * (k3 + r2 * k4)));
    // d(radial)/d(r2) and d(prism)/d(r2); d(r2)/dx = 2x, d(r2)/dy = 2y.
    const double dradial = k1 + r2 * (2 * k2 + r2 * (3 * k3 + r2 * 4 * k4));
    const double dprism_x = s1 + 2 * s2 * r2;
    const double dprism_y = s3 + 2 * s4 * r2;
    // Trefoil: d/dx = 2 (t1 x + t2 y, t2 x - t1 y), d/dy = 2 (t2 x - t1 y, -t1 x - t2 y).
    const double ta = 2 * (t1 * x + t2 * y), tb = 2 * (t2 * x - t1 * y);
    const double dxx =
        radial + x * dradial * 2 * x + 2 * p1 * y + p2 * 6 * x + dprism_x * 2 * x + ta;
    const double dxy = x * dradial * 2 * y + 2 * p1 * x + p2 * 2 * y + dprism_x * 2 * y + tb;
    const double dyx = y * dradial * 2 * x + p1 * 2 * x + 2 * p2 * y + dprism_y * 2 * x + tb;
    const double dyy =
        radial + y * dradial * 2 * y + p1 * 6 * y + 2 * p2 * x + dprism_y * 2 * y - ta;
    // Decentred element: d(d_i g(rho2))/d(x_j) = g delta_ij + 2 d_i d_j g'(rho2),
    // with (d_x, d_y) = (x - dc_x, y - dc_y); its axis offset is a constant.
    const double ddx = x - dc_x, ddy = y - dc_y;
    const double rho2 = ddx * ddx + ddy * ddy;
    const double g = decentred_profile(*this, rho2);
    const double dg = dc_k1 + 2 * dc_k2 * rho2;
    return {dxx + g + 2 * ddx * ddx * dg, dxy + 2 * ddx * ddy * dg, dyx + 2 * ddy * ddx * dg,
            dyy + g + 2 * ddy * ddy * dg};
}

Vec2 LensModel::distorted_to_pixel(Vec2 d) const {
    return {fu * d[0] + skew * d[1] + cu, fv * d[1] + cv};
}

Vec2 LensModel::pixel_to_distorted(Vec2 pixel) const {
    const double yd = (pixel[1] - cv) / fv;
    const double xd = (pixel[0] - cu - skew * yd) / fu;
    return {xd, yd};
}

bool LensModel::undistort(Vec2 d, Vec2& n) const {
    if (!std::isfinite(d[0]) || !std::isfinite(d[1]))
        return false;
    // Newton on F(x) = distort(x) - d from x = d, with step halving whenever a
    // full step does not reduce the residual (strong higher-order terms such
    // as k3 = 5 can overshoot near the field edge).
    Vec2 x = d;
    auto residual = [&](const Vec2& at, Vec2& f) {
        const Vec2 dd = distort(at);
        f = {dd[0] - d[0], dd[1] - d[1]};
        return std::sqrt(f[0] * f[0] + f[1] * f[1]);
    };
    Vec2 f{};
    double res = residual(x, f);
    const double scale = 1 + std::sqrt(d[0] * d[0] + d[1] * d[1]);
    bool converged = false;
    for (int iter = 0; iter < 60 && !converged; ++iter) {
        if (res <= 1e-15 * scale) {
            converged = true;
            break;
        }
        const Mat2 J = distortion_jacobian(x);
        const double det = J[0] * J[3] - J[1] * J[2];
        if (!(std::fabs(det) > 1e-12))
            return false;
        const Vec2 step{(J[3] * f[0] - J[1] * f[1]) / det, (-J[2] * f[0] + J[0] * f[1]) / det};
        double lambda = 1;
        Vec2 trial{};
        Vec2 ftrial{};
        double res_trial = 0;
        int halvings = 0;
        for (;; ++halvings) {
            trial = {x[0] - lambda * step[0], x[1] - lambda * step[1]};
            res_trial = residual(trial, ftrial);
            if (res_trial < res || halvings >= 40)
                break;
            lambda *= 0.5;
        }
        const double step_norm = lambda * std::sqrt(step[0] * step[0] + step[1] * step[1]);
        if (!(res_trial < res)) {
            // No decrease possible: we are at the rounding floor (or stuck).
            converged = res <= 1e-12 * scale;
            break;
        }
        x = trial;
        f = ftrial;
        res = res_trial;
        if (step_norm <= 1e-16 * (1 + std::sqrt(x[0] * x[0] + x[1] * x[1])))
            converged = res <= 1e-12 * scale;
        if (!(std::sqrt(x[0] * x[0] + x[1] * x[1]) < 1e6))
            return false;
    }
    if (!converged && res <= 1e-12 * scale)
        converged = true;
    if (!converged)
        return false;
    // Reject solutions in a folded part of the distortion (far outside the
    // field): there the mapping is not one-to-one and the root is not the ray.
    const Mat2 J = distortion_jacobian(x);
    if (!(J[0] * J[3] - J[1] * J[2] > 0) || !(J[0] > 0) || !(J[3] > 0))
        return false;
    n = x;
    return true;
}

Vec2 LensModel::project(const Vec3& p) const {
    const Vec2 d = distort({p[0] / p[2], p[1] / p[2]});
    return distorted_to_pixel(d);
}

bool LensModel::pixel_to_normalised(Vec2 pixel, Vec2& n) const {
    return undistort(pixel_to_distorted(pixel), n);
}

Mat3 rotation_from_euler_deg(double a, double b, double c) {
    constexpr double deg = 3.14159265358979323846 / 180.0;
    const double ca = std::cos(a * deg), sa = std::sin(a * deg);
    const double cb = std::cos(b * deg), sb = std::sin(b * deg);
    const double cc = std::cos(c * deg), sc = std::sin(c * deg);
    const Mat3 rx{1, 0, 0, 0, ca, -sa, 0, sa, ca};
    const Mat3 ry{cb, 0, sb, 0, 1, 0, -sb, 0, cb};
    const Mat3 rz{cc, -sc, 0, sc, cc, 0, 0, 0, 1};
    return mul(rz, mul(ry, rx));
}

Vec3 mul(const Mat3& m, const Vec3& v) {
    return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
            m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
}

Mat3 transpose(const Mat3& m) {
    return {m[0], m[3], m[6], m[1], m[4], m[7], m[2], m[5], m[8]};
}

Mat3 mul(const Mat3& a, const Mat3& b) {
    Mat3 r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r[i * 3 + j] = a[i * 3] * b[j] + a[i * 3 + 1] * b[3 + j] + a[i * 3 + 2] * b[6 + j];
    return r;
}

} // namespace fpp
