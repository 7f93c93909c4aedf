// The fields a correction grid must not hold in the stereo bundle adjustment
// (see bundle_adjustment.hpp).

#include "bundle_adjustment.hpp"

#include <algorithm>
#include <cmath>

namespace fpp::calib::detail {

// Fields a grid must not hold, per control point (du, dv), each of unit
// norm: constant and linear displacements (the lens model's principal
// point, focal lengths and skew, and a turn about the optical axis) and
// the image motion of a small turn about the x or y axis (through the
// lens's distortion). A grid free to hold them would make a turn of the
// device's frame unobservable: the frame would drift (rays turned by
// ~5e-4 rad, measured) while the residuals stayed the same.
std::vector<std::vector<Vec2>> gauge_fields(const CorrectionGrid& grid, const LensModel& lens) {
    std::vector<std::vector<Vec2>> fields;
    if (grid.empty())
        return fields;
    const double su = double(grid.image().width) / double(grid.columns() - 3);
    const double sv = double(grid.image().height) / double(grid.rows() - 3);
    // Control point k's place (its B-spline's centre), clamped to the
    // image (outside it a strong lens may fold), in pixels and as an
    // undistorted normalised point with the distortion's Jacobian there.
    struct Place {
        double u, v, x, y;
        Mat2 J;
    };
    std::vector<Place> places;
    for (int j = 0; j < grid.rows(); ++j)
        for (int i = 0; i < grid.columns(); ++i) {
            Place p{};
            p.u = std::clamp((i - 1) * su - 0.5, 0.0, grid.image().width - 1.0);
            p.v = std::clamp((j - 1) * sv - 0.5, 0.0, grid.image().height - 1.0);
            Vec2 n{};
            if (!lens.pixel_to_normalised({p.u, p.v}, n))
                n = lens.pixel_to_distorted({p.u, p.v});
            p.x = n[0];
            p.y = n[1];
            p.J = lens.distortion_jacobian(n);
            places.push_back(p);
        }
    const auto field = [&](auto f) {
        std::vector<Vec2> v;
        double norm = 0;
        for (const Place& p : places) {
            const Vec2 d = f(p);
            norm += d[0] * d[0] + d[1] * d[1];
            v.push_back(d);
        }
        const double scale = 1 / std::sqrt(norm);
        for (Vec2& d : v)
            d = {d[0] * scale, d[1] * scale};
        fields.push_back(std::move(v));
    };
    // Image motion (px) of an undistorted normalised motion (dx, dy).
    const auto pixel_motion = [&](const Place& p, double dx, double dy) {
        const double ddx = p.J[0] * dx + p.J[1] * dy, ddy = p.J[2] * dx + p.J[3] * dy;
        return Vec2{lens.fu * ddx + lens.skew * ddy, lens.fv * ddy};
    };
    field([](const Place&) { return Vec2{1, 0}; });
    field([](const Place&) { return Vec2{0, 1}; });
    field([](const Place& p) { return Vec2{p.u, 0}; });
    field([](const Place& p) { return Vec2{p.v, 0}; });
    field([](const Place& p) { return Vec2{0, p.u}; });
    field([](const Place& p) { return Vec2{0, p.v}; });
    field([&](const Place& p) { return pixel_motion(p, p.x * p.y, 1 + p.y * p.y); });
    field([&](const Place& p) { return pixel_motion(p, 1 + p.x * p.x, p.x * p.y); });
    // The distortion terms' own fields (k1 k2 k3 p1 p2): with them the
    // model's parameters and a turn could trade places through the grid
    // (a turn about y is nearly a principal point shift and a p2 change).
    const auto distortion_motion = [&](const Place&, double dxd, double dyd) {
        return Vec2{lens.fu * dxd + lens.skew * dyd, lens.fv * dyd};
    };
    field([&](const Place& p) {
        const double r2 = p.x * p.x + p.y * p.y;
        return distortion_motion(p, p.x * r2, p.y * r2);
    });
    field([&](const Place& p) {
        const double r4 = std::pow(p.x * p.x + p.y * p.y, 2);
        return distortion_motion(p, p.x * r4, p.y * r4);
    });
    field([&](const Place& p) {
        const double r6 = std::pow(p.x * p.x + p.y * p.y, 3);
        return distortion_motion(p, p.x * r6, p.y * r6);
    });
    field([&](const Place& p) {
        const double r2 = p.x * p.x + p.y * p.y;
        return distortion_motion(p, 2 * p.x * p.y, r2 + 2 * p.y * p.y);
    });
    field([&](const Place& p) {
        const double r2 = p.x * p.x + p.y * p.y;
        return distortion_motion(p, r2 + 2 * p.x * p.x, 2 * p.x * p.y);
    });
    return fields;
}

} // namespace fpp::calib::detail
