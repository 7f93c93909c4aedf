// Ray intersection of the simulator's shapes (camera frame, mm).

#include "fpp/simulator/scene.hpp"

#include "fpp/vec3.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace fpp::sim {

using namespace vec;

namespace {

void face_ray(Hit& hit, const Vec3& d) {
    if (dot(hit.normal, d) > 0)
        hit.normal = scale(hit.normal, -1.0);
}

void require_albedo(double albedo, const char* what) {
    if (!(albedo >= 0 && albedo <= 1))
        throw std::invalid_argument(std::string(what) + ": albedo must be in [0, 1]");
}

} // namespace

// ---- SpecularLobe ----------------------------------------------------------

double SpecularLobe::relative_reflectance(double cos_h) const {
    if (!(specular > 0) || !(cos_h > 0))
        return 0;
    return specular * (shininess + 8) / 8 * std::pow(std::min(cos_h, 1.0), shininess);
}

double SpecularLobe::shininess_from_roughness(double roughness) {
    return 2 / (roughness * roughness) - 2;
}

void SpecularLobe::validate(double albedo) const {
    if (!(specular >= 0 && specular <= 1))
        throw std::invalid_argument("specular must be in [0, 1]");
    if (specular > 0 && !(shininess >= 1 && shininess <= 1e5))
        throw std::invalid_argument("shininess must be in [1, 1e5]");
    // Reflected energy cannot exceed the incident one.
    if (!(albedo + specular <= 1 + 1e-12))
        throw std::invalid_argument("albedo + specular must not exceed 1");
}

// ---- Pose ----------------------------------------------------------------

Pose Pose::from_euler_deg(const Vec3& centre, double a, double b, double c) {
    return {centre, rotation_from_euler_deg(a, b, c)};
}

Vec3 Pose::to_camera(const Vec3& local) const {
    return add(centre, mul(R, local));
}

Vec3 Pose::to_local(const Vec3& camera) const {
    return mul(transpose(R), sub(camera, centre));
}

// ---- Plane ---------------------------------------------------------------

Plane::Plane(const Pose& pose, double width, double height, double albedo)
    : pose_(pose), half_width_(width / 2), half_height_(height / 2), albedo_(albedo) {
    if (!(width > 0) || !(height > 0))
        throw std::invalid_argument("Plane: size must be positive");
    require_albedo(albedo, "Plane");
}

bool Plane::hit_plane(const Vec3& o, const Vec3& d, double tmin, double tmax, double& t, double& x,
                      double& y) const {
    const Vec3 n = column(pose_.R, 2);
    const double dn = dot(d, n);
    if (std::fabs(dn) < 1e-15)
        return false;
    t = dot(sub(pose_.centre, o), n) / dn;
    if (!(t > tmin && t < tmax))
        return false;
    const Vec3 rel = sub(add(o, scale(d, t)), pose_.centre);
    x = dot(rel, column(pose_.R, 0));
    y = dot(rel, column(pose_.R, 1));
    return true;
}

bool Plane::intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, Hit& hit) const {
    double t = 0, x = 0, y = 0;
    if (!hit_plane(o, d, tmin, tmax, t, x, y))
        return false;
    if (std::fabs(x) > half_width_ || std::fabs(y) > half_height_)
        return false;
    hit.t = t;
    hit.point = add(o, scale(d, t));
    hit.normal = column(pose_.R, 2);
    hit.albedo = albedo_;
    face_ray(hit, d);
    return true;
}

// ---- Checkerboard ---------------------------------------------------------

namespace {
double checker_half_extent(int inner, double square, double margin) {
    return (inner + 1) * square / 2 + margin;
}
} // namespace

Checkerboard::Checkerboard(const Pose& pose, const CheckerboardSpec& spec)
    : Plane(pose, 2 * checker_half_extent(spec.inner_columns, spec.square_size, spec.margin),
            2 * checker_half_extent(spec.inner_rows, spec.square_size, spec.margin),
            spec.white_albedo),
      spec_(spec) {
    if (spec.inner_columns < 2 || spec.inner_rows < 2)
        throw std::invalid_argument("Checkerboard: at least 2 x 2 inner corners");
    if (!(spec.square_size > 0) || !(spec.margin >= 0))
        throw std::invalid_argument("Checkerboard: square size must be positive, margin >= 0");
    require_albedo(spec.black_albedo, "Checkerboard");
    require_albedo(spec.white_albedo, "Checkerboard");
}

double Checkerboard::albedo_at(double x, double y) const {
    const double s = spec_.square_size;
    // Square index m covers x in [corner(m-1), corner(m)], corner(i) = (i - (cols-1)/2) s.
    const double fx = x / s + (spec_.inner_columns + 1) * 0.5;
    const double fy = y / s + (spec_.inner_rows + 1) * 0.5;
    if (fx < 0 || fy < 0 || fx >= spec_.inner_columns + 1 || fy >= spec_.inner_rows + 1)
        return spec_.white_albedo; // margin
    const long m = static_cast<long>(std::floor(fx));
    const long n = static_cast<long>(std::floor(fy));
    return ((m + n) % 2 == 0) ? spec_.black_albedo : spec_.white_albedo;
}

bool Checkerboard::intersect(const Vec3& o, const Vec3& d, double tmin, double tmax,
                             Hit& hit) const {
    if (!Plane::intersect(o, d, tmin, tmax, hit))
        return false;
    const Vec3 rel = sub(hit.point, pose_.centre);
    hit.albedo = albedo_at(dot(rel, column(pose_.R, 0)), dot(rel, column(pose_.R, 1)));
    return true;
}

namespace {

// Area of the convex polygon `poly` (n vertices) clipped to the rectangle
// [x0, x1] x [y0, y1] (Sutherland-Hodgman; fixed-size buffers, no allocation).
double clipped_area(const std::array<Vec2, 4>& quad, double x0, double x1, double y0, double y1) {
    std::array<Vec2, 12> a{}, b{};
    int n = 4;
    for (int i = 0; i < 4; ++i)
        a[static_cast<std::size_t>(i)] = quad[static_cast<std::size_t>(i)];
    // Keep the side where sign * (coord - bound) <= 0, for each of the four edges.
    const struct {
        int axis;
        double bound, sign;
    } planes[4] = {{0, x0, -1}, {0, x1, 1}, {1, y0, -1}, {1, y1, 1}};
    for (const auto& pl : planes) {
        int m = 0;
        for (int i = 0; i < n; ++i) {
            const Vec2& p = a[static_cast<std::size_t>(i)];
            const Vec2& q = a[static_cast<std::size_t>((i + 1) % n)];
            const double dp = pl.sign * (p[static_cast<std::size_t>(pl.axis)] - pl.bound);
            const double dq = pl.sign * (q[static_cast<std::size_t>(pl.axis)] - pl.bound);
            if (dp <= 0)
                b[static_cast<std::size_t>(m++)] = p;
            if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
                const double t = dp / (dp - dq);
                b[static_cast<std::size_t>(m++)] = {p[0] + t * (q[0] - p[0]),
                                                    p[1] + t * (q[1] - p[1])};
            }
        }
        n = m;
        a = b;
        if (n < 3)
            return 0;
    }
    double twice = 0;
    for (int i = 0; i < n; ++i) {
        const Vec2& p = a[static_cast<std::size_t>(i)];
        const Vec2& q = a[static_cast<std::size_t>((i + 1) % n)];
        twice += p[0] * q[1] - q[0] * p[1];
    }
    return 0.5 * std::fabs(twice);
}

} // namespace

double Checkerboard::footprint_albedo(const Hit& hit, const Vec3& dpdu, const Vec3& dpdv) const {
    const Vec3 ex = column(pose_.R, 0), ey = column(pose_.R, 1);
    const Vec3 rel = sub(hit.point, pose_.centre);
    // Everything in square units: cell (m, n) is [m, m+1) x [n, n+1).
    const double s = spec_.square_size;
    const double fx = dot(rel, ex) / s + (spec_.inner_columns + 1) * 0.5;
    const double fy = dot(rel, ey) / s + (spec_.inner_rows + 1) * 0.5;
    const Vec2 a{dot(dpdu, ex) / s, dot(dpdu, ey) / s};
    const Vec2 b{dot(dpdv, ex) / s, dot(dpdv, ey) / s};
    const double area = std::fabs(a[0] * b[1] - a[1] * b[0]);
    const double rx = 0.5 * (std::fabs(a[0]) + std::fabs(b[0]));
    const double ry = 0.5 * (std::fabs(a[1]) + std::fabs(b[1]));
    if (!std::isfinite(area) || !(area > 0) || rx > 2 || ry > 2)
        return hit.albedo;
    const long m0 = static_cast<long>(std::floor(fx - rx)),
               m1 = static_cast<long>(std::floor(fx + rx));
    const long n0 = static_cast<long>(std::floor(fy - ry)),
               n1 = static_cast<long>(std::floor(fy + ry));
    if (m0 == m1 && n0 == n1)
        return hit.albedo; // inside one square (or the margin)
    // Exact box filter over the pixel's footprint (a parallelogram on the
    // board): the area of its overlap with each square it touches.
    const std::array<Vec2, 4> quad{
        Vec2{fx - 0.5 * a[0] - 0.5 * b[0], fy - 0.5 * a[1] - 0.5 * b[1]},
        Vec2{fx + 0.5 * a[0] - 0.5 * b[0], fy + 0.5 * a[1] - 0.5 * b[1]},
        Vec2{fx + 0.5 * a[0] + 0.5 * b[0], fy + 0.5 * a[1] + 0.5 * b[1]},
        Vec2{fx - 0.5 * a[0] + 0.5 * b[0], fy - 0.5 * a[1] + 0.5 * b[1]}};
    double sum = 0;
    for (long n = n0; n <= n1; ++n)
        for (long m = m0; m <= m1; ++m) {
            const double part =
                clipped_area(quad, static_cast<double>(m), static_cast<double>(m + 1),
                             static_cast<double>(n), static_cast<double>(n + 1));
            if (part <= 0)
                continue;
            const bool in_pattern =
                m >= 0 && n >= 0 && m <= spec_.inner_columns && n <= spec_.inner_rows;
            sum +=
                part * ((in_pattern && (m + n) % 2 == 0) ? spec_.black_albedo : spec_.white_albedo);
        }
    return sum / area;
}

std::vector<Vec3> Checkerboard::inner_corners() const {
    std::vector<Vec3> corners;
    corners.reserve(static_cast<std::size_t>(spec_.inner_columns * spec_.inner_rows));
    const double s = spec_.square_size;
    for (int j = 0; j < spec_.inner_rows; ++j)
        for (int i = 0; i < spec_.inner_columns; ++i)
            corners.push_back(pose_.to_camera({(i - (spec_.inner_columns - 1) * 0.5) * s,
                                               (j - (spec_.inner_rows - 1) * 0.5) * s, 0.0}));
    return corners;
}

// ---- Sphere --------------------------------------------------------------

Sphere::Sphere(const Vec3& centre, double radius, double albedo)
    : centre_(centre), radius_(radius), albedo_(albedo) {
    if (!(radius > 0))
        throw std::invalid_argument("Sphere: radius must be positive");
    require_albedo(albedo, "Sphere");
}

bool Sphere::intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, Hit& hit) const {
    const Vec3 oc = sub(o, centre_);
    const double b = dot(oc, d);
    // c computed as (|oc| - r)(|oc| + r) keeps precision for rays starting on the surface.
    const double len = norm(oc);
    const double c = (len - radius_) * (len + radius_);
    const double disc = b * b - c;
    if (disc < 0)
        return false;
    const double sq = std::sqrt(disc);
    // Stable roots: q = -(b + sign(b) sq); t = q and c / q.
    const double q = -(b + std::copysign(sq, b));
    double t0 = q, t1 = q != 0 ? c / q : 0.0;
    if (t0 > t1)
        std::swap(t0, t1);
    double t = t0;
    if (!(t > tmin && t < tmax)) {
        t = t1;
        if (!(t > tmin && t < tmax))
            return false;
    }
    hit.t = t;
    hit.point = add(o, scale(d, t));
    hit.normal = scale(sub(hit.point, centre_), 1.0 / radius_);
    hit.albedo = albedo_;
    face_ray(hit, d);
    return true;
}

// ---- Cylinder ------------------------------------------------------------

Cylinder::Cylinder(const Vec3& centre, const Vec3& axis, double radius, double length,
                   double albedo)
    : centre_(centre), axis_(normalised(axis)), radius_(radius), half_length_(length / 2),
      albedo_(albedo) {
    if (!(radius > 0) || !(length > 0))
        throw std::invalid_argument("Cylinder: radius and length must be positive");
    if (!(norm(axis) > 0))
        throw std::invalid_argument("Cylinder: axis must be non-zero");
    require_albedo(albedo, "Cylinder");
}

bool Cylinder::intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, Hit& hit) const {
    const Vec3 oc = sub(o, centre_);
    const double oa = dot(oc, axis_), da = dot(d, axis_);
    const Vec3 op = sub(oc, scale(axis_, oa)); // components across the axis
    const Vec3 dp = sub(d, scale(axis_, da));
    double best = tmax;
    Vec3 best_normal{};
    bool found = false;
    // Lateral surface: |op + t dp| = r.
    const double A = dot(dp, dp);
    if (A > 1e-18) {
        const double B = dot(op, dp);
        const double len = norm(op);
        const double C = (len - radius_) * (len + radius_);
        const double disc = B * B - A * C;
        if (disc >= 0) {
            const double sq = std::sqrt(disc);
            const double q = -(B + std::copysign(sq, B));
            const double roots[2] = {q / A, q != 0 ? C / q : -1.0};
            for (double t : roots) {
                if (!(t > tmin && t < best))
                    continue;
                const double along = oa + t * da;
                if (std::fabs(along) > half_length_)
                    continue;
                best = t;
                best_normal = normalised(add(op, scale(dp, t)));
                found = true;
            }
        }
    }
    // End caps.
    if (std::fabs(da) > 1e-15) {
        for (double side : {-1.0, 1.0}) {
            const double t = (side * half_length_ - oa) / da;
            if (!(t > tmin && t < best))
                continue;
            const Vec3 across = add(op, scale(dp, t));
            if (dot(across, across) > radius_ * radius_)
                continue;
            best = t;
            best_normal = scale(axis_, side);
            found = true;
        }
    }
    if (!found)
        return false;
    hit.t = best;
    hit.point = add(o, scale(d, best));
    hit.normal = best_normal;
    hit.albedo = albedo_;
    face_ray(hit, d);
    return true;
}

// ---- Relief --------------------------------------------------------------

std::vector<ReliefBump> Relief::face_bumps() {
    // Local y grows downward in the image when R = I (camera y points down).
    return {
        {0, 0, 32, 118, 167},                          // head dome
        {0, -52, 4, 98, 34},                           // forehead
        {-27, -28, 5, 39, 12},                         // brows
        {27, -28, 5, 39, 12},  {-27, -12, -9, 29, 20}, // eye hollows
        {27, -12, -9, 29, 20}, {0, 8, 16, 17, 49},     // nose ridge
        {0, 24, 6, 27, 15},                            // nose tip and wings
        {-36, 22, 6, 39, 37},                          // cheeks
        {36, 22, 6, 39, 37},   {0, 46, 3.5, 39, 10},   // lips
        {0, 55, -2, 34, 7},                            // below the lips
        {0, 72, 7, 49, 29},                            // chin
    };
}

Relief::Relief(const Pose& pose, double width, double height, std::vector<ReliefBump> bumps,
               double albedo)
    : pose_(pose), half_width_(width / 2), half_height_(height / 2), albedo_(albedo),
      bumps_(std::move(bumps)) {
    if (!(width > 0) || !(height > 0))
        throw std::invalid_argument("Relief: size must be positive");
    require_albedo(albedo, "Relief");
    double hessian_bound = 0;
    for (const ReliefBump& b : bumps_) {
        if (!(b.radius_x > 0) || !(b.radius_y > 0) || !std::isfinite(b.radius_x) ||
            !std::isfinite(b.radius_y))
            throw std::invalid_argument("Relief: bump radii must be positive");
        if (!std::isfinite(b.amplitude) || !std::isfinite(b.x0) || !std::isfinite(b.y0))
            throw std::invalid_argument("Relief: non-finite bump");
        const double r = std::min(b.radius_x, b.radius_y);
        // For A (1 - q)^3: |d2/du2| <= 12 |A|, |d2/dudv| <= 3 |A| in the
        // scaled coordinates u = (x - x0) / rx, v = (y - y0) / ry, so the
        // Hessian's Frobenius norm is below 18 |A| / min(rx, ry)^2.
        hessian_bound += 18 * std::fabs(b.amplitude) / (r * r);
        scaled_.push_back({b.x0, b.y0, b.amplitude, 1 / b.radius_x, 1 / b.radius_y});
    }
    // Cells of about 2 mm, sampled by a node grid 4 times finer. Between nodes
    // |grad h| exceeds the nodes' maximum by at most hessian_bound * reach and
    // h exceeds it by at most slope * reach (reach: farthest distance from a
    // node), so the cell bounds are strict.
    constexpr int kSub = 4;
    cells_x_ = std::clamp(static_cast<int>(std::ceil(width / 2.0)), 1, 512);
    cells_y_ = std::clamp(static_cast<int>(std::ceil(height / 2.0)), 1, 512);
    cell_w_ = width / cells_x_;
    cell_h_ = height / cells_y_;
    const int nx = cells_x_ * kSub + 1, ny = cells_y_ * kSub + 1;
    const double sx = cell_w_ / kSub, sy = cell_h_ / kSub;
    const double reach = 0.5 * std::hypot(sx, sy);
    std::vector<double> node_h(static_cast<std::size_t>(nx) * ny), node_g(node_h.size());
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            double gx = 0, gy = 0;
            const std::size_t k = static_cast<std::size_t>(j) * nx + i;
            node_h[k] = eval(-half_width_ + i * sx, -half_height_ + j * sy, &gx, &gy);
            node_g[k] = std::hypot(gx, gy);
        }
    cells_.resize(static_cast<std::size_t>(cells_x_) * cells_y_);
    h_min_ = std::numeric_limits<double>::max();
    h_max_ = -h_min_;
    slope_bound_ = 0;
    for (int cy = 0; cy < cells_y_; ++cy)
        for (int cx = 0; cx < cells_x_; ++cx) {
            double lo = std::numeric_limits<double>::max(), hi = -lo, g = 0;
            for (int j = cy * kSub; j <= (cy + 1) * kSub; ++j)
                for (int i = cx * kSub; i <= (cx + 1) * kSub; ++i) {
                    const std::size_t k = static_cast<std::size_t>(j) * nx + i;
                    lo = std::min(lo, node_h[k]);
                    hi = std::max(hi, node_h[k]);
                    g = std::max(g, node_g[k]);
                }
            Cell& c = cells_[static_cast<std::size_t>(cy) * cells_x_ + cx];
            c.slope = g + hessian_bound * reach;
            c.h_min = lo - c.slope * reach;
            c.h_max = hi + c.slope * reach;
            h_min_ = std::min(h_min_, c.h_min);
            h_max_ = std::max(h_max_, c.h_max);
            slope_bound_ = std::max(slope_bound_, c.slope);
        }
    // Bump lists per cell (closed rectangles with a margin, so that points
    // on a shared border see the same bumps from both cells).
    constexpr double kMargin = 1e-6;
    cell_offset_.assign(cells_.size() + 1, 0);
    for (int cy = 0; cy < cells_y_; ++cy)
        for (int cx = 0; cx < cells_x_; ++cx) {
            const double x0 = -half_width_ + cx * cell_w_ - kMargin,
                         x1 = x0 + cell_w_ + 2 * kMargin;
            const double y0 = -half_height_ + cy * cell_h_ - kMargin,
                         y1 = y0 + cell_h_ + 2 * kMargin;
            for (std::size_t k = 0; k < bumps_.size(); ++k) {
                const ReliefBump& b = bumps_[k];
                if (b.x0 + b.radius_x < x0 || b.x0 - b.radius_x > x1 || b.y0 + b.radius_y < y0 ||
                    b.y0 - b.radius_y > y1)
                    continue;
                cell_bumps_.push_back(scaled_[k]);
            }
            cell_offset_[static_cast<std::size_t>(cy) * cells_x_ + cx + 1] = cell_bumps_.size();
        }
}

double Relief::eval_range(const ScaledBump* begin, const ScaledBump* end, double x, double y,
                          double* gx, double* gy) {
    double h = 0, sx = 0, sy = 0;
    for (const ScaledBump* b = begin; b != end; ++b) {
        const double u = (x - b->x0) * b->inv_rx, v = (y - b->y0) * b->inv_ry;
        const double m = std::max(0.0, 1 - (u * u + v * v));
        const double am2 = b->amplitude * m * m;
        h += am2 * m;
        // d/dx A (1 - q)^3 = -6 A u (1 - q)^2 / rx.
        sx -= 6 * am2 * u * b->inv_rx;
        sy -= 6 * am2 * v * b->inv_ry;
    }
    if (gx)
        *gx = sx;
    if (gy)
        *gy = sy;
    return h;
}

double Relief::eval(double x, double y, double* gx, double* gy) const {
    return eval_range(scaled_.data(), scaled_.data() + scaled_.size(), x, y, gx, gy);
}

double Relief::height_at(double x, double y) const {
    return eval(x, y, nullptr, nullptr);
}

Vec2 Relief::gradient_at(double x, double y) const {
    Vec2 g{};
    eval(x, y, &g[0], &g[1]);
    return g;
}

Vec3 Relief::surface_point(double x, double y) const {
    return pose_.to_camera({x, y, -height_at(x, y)});
}

Relief::LocalRay Relief::local_ray(const Vec3& o, const Vec3& d) const {
    const Vec3 ex = column(pose_.R, 0), ey = column(pose_.R, 1), ez = column(pose_.R, 2);
    const Vec3 rel = sub(o, pose_.centre);
    return {dot(rel, ex), dot(rel, ey), -dot(rel, ez), dot(d, ex), dot(d, ey), -dot(d, ez)};
}

bool Relief::clip_to_box(const LocalRay& r, double& t0, double& t1) const {
    // The box |x| <= W/2, |y| <= H/2, w in [h_min, h_max] (slab method).
    auto slab = [&](double origin, double dir, double lo, double hi) {
        if (std::fabs(dir) < 1e-300)
            return origin >= lo && origin <= hi;
        double a = (lo - origin) / dir, b = (hi - origin) / dir;
        if (a > b)
            std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
        return t0 <= t1;
    };
    return slab(r.ox, r.dx, -half_width_, half_width_) &&
           slab(r.oy, r.dy, -half_height_, half_height_) && slab(r.ow, r.dw, h_min_, h_max_);
}

double Relief::height_gap(const LocalRay& r, const ScaledBump* begin, const ScaledBump* end,
                          double t) {
    return r.ow + t * r.dw -
           eval_range(begin, end, r.ox + t * r.dx, r.oy + t * r.dy, nullptr, nullptr);
}

double Relief::cell_exit(const LocalRay& r, double at, double t1, int& cx, int& cy) const {
    const double x = r.ox + at * r.dx, y = r.oy + at * r.dy;
    cx = std::clamp(static_cast<int>(std::floor((x + half_width_) / cell_w_)), 0, cells_x_ - 1);
    cy = std::clamp(static_cast<int>(std::floor((y + half_height_) / cell_h_)), 0, cells_y_ - 1);
    double te = t1;
    if (r.dx > 0)
        te = std::min(te, (-half_width_ + (cx + 1) * cell_w_ - r.ox) / r.dx);
    if (r.dx < 0)
        te = std::min(te, (-half_width_ + cx * cell_w_ - r.ox) / r.dx);
    if (r.dy > 0)
        te = std::min(te, (-half_height_ + (cy + 1) * cell_h_ - r.oy) / r.dy);
    if (r.dy < 0)
        te = std::min(te, (-half_height_ + cy * cell_h_ - r.oy) / r.dy);
    // Guarantee progress when the point sits on a cell border.
    return std::max(te, at + 1e-9 * (1 + std::fabs(at)));
}

bool Relief::bracket_crossing(const LocalRay& r, double t, double ft, double t1,
                              Bracket& out) const {
    // Walk the cells the ray crosses: a cell whose height range the ray stays
    // above (or below, if it started below) cannot hold a crossing; elsewhere
    // |f'| <= |dw| + L_cell |d_xy|, so a step of |f| / rate cannot pass the
    // first root.
    const ScaledBump* bb = scaled_.data(); // bumps of the current cell
    const ScaledBump* be = scaled_.data() + scaled_.size();
    const double dxy = std::sqrt(r.dx * r.dx + r.dy * r.dy);
    constexpr double kMinStep = 1e-3; // mm; a crossing inside one such step is bracketed
    const bool positive = ft > 0;
    bool ft_known = true;
    for (long iter = 0; iter < 4000000 && t < t1; ++iter) {
        int cx = 0, cy = 0;
        const double te = std::min(cell_exit(r, t, t1, cx, cy), t1);
        const std::size_t ci = static_cast<std::size_t>(cy) * cells_x_ + cx;
        const Cell& c = cells_[ci];
        const double wa = r.ow + t * r.dw, wb = r.ow + te * r.dw;
        if (positive ? std::min(wa, wb) > c.h_max : std::max(wa, wb) < c.h_min) {
            t = te; // no crossing in this cell
            ft_known = false;
            continue;
        }
        bb = cell_bumps_.data() + cell_offset_[ci];
        be = cell_bumps_.data() + cell_offset_[ci + 1];
        if (!ft_known) {
            ft = height_gap(r, bb, be, t);
            ft_known = true;
            if ((ft > 0) != positive || ft == 0) { // only at a cell border, by rounding
                out = {t, ft, t, ft, bb, be};
                return true;
            }
        }
        const double rate = std::fabs(r.dw) + c.slope * dxy;
        while (t < te) {
            const double step = std::max(std::fabs(ft) / rate, kMinStep);
            const double tn = std::min(t + step, te);
            const double fn = height_gap(r, bb, be, tn);
            if ((fn > 0) != positive || fn == 0) {
                out = {t, ft, tn, fn, bb, be};
                return true;
            }
            t = tn;
            ft = fn;
        }
    }
    return false;
}

double Relief::refine_crossing(const LocalRay& r, Bracket br) {
    // Keep the bracket [a, b], fall back to bisection.
    double a = br.a, fa = br.fa, b = br.b, fb = br.fb;
    double t = 0.5 * (a + b);
    for (int iter = 0; iter < 200; ++iter) {
        if (fb == 0) {
            t = b;
            break;
        }
        double gx = 0, gy = 0;
        const double x = r.ox + t * r.dx, y = r.oy + t * r.dy;
        const double ftt =
            r.ow + t * r.dw - eval_range(br.bumps_begin, br.bumps_end, x, y, &gx, &gy);
        if (ftt == 0)
            break;
        if ((ftt > 0) == (fa > 0)) {
            a = t;
            fa = ftt;
        } else {
            b = t;
            fb = ftt;
        }
        if (b - a <= 1e-10) {
            t = 0.5 * (a + b);
            break;
        }
        const double df = r.dw - gx * r.dx - gy * r.dy;
        double tn = df != 0 ? t - ftt / df : 0.5 * (a + b);
        if (!(tn > a && tn < b))
            tn = 0.5 * (a + b);
        if (std::fabs(tn - t) <= 1e-11) {
            t = tn;
            break;
        }
        t = tn;
    }
    return t;
}

bool Relief::surface_hit(const Vec3& o, const Vec3& d, const LocalRay& r, double t,
                         Hit& hit) const {
    const double x = r.ox + t * r.dx, y = r.oy + t * r.dy;
    double gx = 0, gy = 0;
    eval(x, y, &gx, &gy);
    if (std::fabs(x) > half_width_ || std::fabs(y) > half_height_)
        return false;
    const Vec3 ex = column(pose_.R, 0), ey = column(pose_.R, 1), ez = column(pose_.R, 2);
    hit.t = t;
    hit.point = add(o, scale(d, t));
    // Surface s(x, y) = x ex + y ey + h ew with ew = -ez; normal ~ -gx ex - gy ey + ew.
    hit.normal = normalised(sub(sub(scale(ez, -1.0), scale(ex, gx)), scale(ey, gy)));
    hit.albedo = albedo_;
    face_ray(hit, d);
    return true;
}

bool Relief::intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, Hit& hit) const {
    const LocalRay r = local_ray(o, d);
    double t0 = tmin, t1 = tmax;
    if (!clip_to_box(r, t0, t1))
        return false;
    double t = t0;
    const double ft = height_gap(r, scaled_.data(), scaled_.data() + scaled_.size(), t);
    if (ft == 0) {
        if (!(t > tmin))
            t = std::nextafter(t, t1);
    } else {
        Bracket bracket{};
        if (!bracket_crossing(r, t, ft, t1, bracket))
            return false;
        t = refine_crossing(r, bracket);
        if (!(t > tmin && t < tmax))
            return false;
    }
    return surface_hit(o, d, r, t, hit);
}

// ---- Scene ---------------------------------------------------------------

void Scene::add(std::unique_ptr<Shape> shape, std::string name, const SpecularLobe& specular) {
    if (!shape)
        throw std::invalid_argument("Scene::add: null shape");
    // The lobe's energy bound is checked against the shape's largest albedo
    // by the scene readers; here only its own ranges.
    specular.validate(0);
    if (name.empty())
        name = "object" + std::to_string(shapes_.size());
    shapes_.reserve(shapes_.size() + 1);
    names_.reserve(shapes_.size() + 1);
    specular_.reserve(shapes_.size() + 1);
    shapes_.push_back(std::move(shape));
    names_.push_back(std::move(name));
    specular_.push_back(specular);
}

bool Scene::intersect(const Vec3& o, const Vec3& d, Hit& hit) const {
    double tmax = std::numeric_limits<double>::infinity();
    bool found = false;
    for (std::size_t i = 0; i < shapes_.size(); ++i) {
        Hit h;
        if (shapes_[i]->intersect(o, d, kEpsilon, tmax, h)) {
            h.object = static_cast<int>(i);
            hit = h;
            tmax = h.t;
            found = true;
        }
    }
    return found;
}

bool Scene::occluded(const Vec3& o, const Vec3& d, double tmax) const {
    Hit h;
    for (const auto& s : shapes_)
        if (s->intersect(o, d, kEpsilon, tmax, h))
            return true;
    return false;
}

void add_ball_bar(Scene& scene, const Vec3& centre, const Vec3& axis, double distance,
                  double radius, double albedo, const std::string& name,
                  const SpecularLobe& specular) {
    if (!(distance > 2 * radius))
        throw std::invalid_argument("ball bar: distance must exceed the sphere diameter");
    specular.validate(albedo);
    const Vec3 a = normalised(axis);
    scene.add(std::make_unique<Sphere>(sub(centre, scale(a, distance / 2)), radius, albedo), name,
              specular);
    scene.add(std::make_unique<Sphere>(add(centre, scale(a, distance / 2)), radius, albedo), name,
              specular);
}

} // namespace fpp::sim
