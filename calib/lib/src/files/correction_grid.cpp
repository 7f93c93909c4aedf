// Dense lens correction: a bicubic B-spline displacement field (see
// fpp/calib/correction_grid.hpp).

#include "fpp/calib/correction_grid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace fpp::calib {

namespace {

// Uniform cubic B-spline basis at fraction f of an interval, and its derivative.
void basis(double f, double b[4]) {
    const double g = 1 - f, f2 = f * f, f3 = f2 * f;
    b[0] = g * g * g / 6;
    b[1] = (3 * f3 - 6 * f2 + 4) / 6;
    b[2] = (-3 * f3 + 3 * f2 + 3 * f + 1) / 6;
    b[3] = f3 / 6;
}

void basis_derivative(double f, double b[4]) {
    const double g = 1 - f, f2 = f * f;
    b[0] = -g * g / 2;
    b[1] = (9 * f2 - 12 * f) / 6;
    b[2] = (-9 * f2 + 6 * f + 3) / 6;
    b[3] = f2 / 2;
}

} // namespace

CorrectionGrid::CorrectionGrid(Size image, int columns, int rows)
    : image_(image), columns_(columns), rows_(rows) {
    if (columns < 4 || rows < 4)
        throw std::invalid_argument("correction grid: at least 4 x 4 control points, got " +
                                    std::to_string(columns) + " x " + std::to_string(rows));
    if (image.width < 2 || image.height < 2)
        throw std::invalid_argument("correction grid: image size must be positive");
    spacing_x_ = double(image.width) / double(columns - 3);
    spacing_y_ = double(image.height) / double(rows - 3);
    values_.assign(std::size_t(columns * rows), Vec2{0, 0});
}

double CorrectionGrid::largest_control_value() const {
    double m = 0;
    for (const Vec2& v : values_)
        m = std::max(m, std::hypot(v[0], v[1]));
    return m;
}

void CorrectionGrid::locate(double pixel, double spacing, int intervals, int& first,
                            double& f) const {
    const double s = (pixel + 0.5) / spacing;
    // Truncation is the floor wherever the clamp does not decide (s >= 0),
    // without a call to floor() on a processor without SSE4.1.
    first = std::clamp(static_cast<int>(s), 0, intervals - 1);
    f = s - first; // outside [0, 1] beyond the image: the edge polynomial continues
}

// The spline's basis at a pixel: first control point and the weights
// along each axis (and, when asked, their derivatives per pixel).
struct CorrectionGrid::Basis {
    int i0 = 0, j0 = 0;
    double bx[4], by[4], dx[4], dy[4];
};

CorrectionGrid::Basis CorrectionGrid::basis_at(Vec2 pixel, bool derivatives) const {
    Basis b;
    double fx, fy;
    locate(pixel[0], spacing_x_, columns_ - 3, b.i0, fx);
    locate(pixel[1], spacing_y_, rows_ - 3, b.j0, fy);
    basis(fx, b.bx);
    basis(fy, b.by);
    if (derivatives) {
        basis_derivative(fx, b.dx);
        basis_derivative(fy, b.dy);
        for (int k = 0; k < 4; ++k) {
            b.dx[k] /= spacing_x_;
            b.dy[k] /= spacing_y_;
        }
    }
    return b;
}

// The field and its derivatives at a basis, summed row by row of control
// points (the spline is a tensor product: 4 sums of 4 per row, then one of
// 4, in short independent chains).
void CorrectionGrid::evaluate(const Basis& s, bool derivatives, Vec2& delta, Mat2& J) const {
    delta = {0, 0};
    J = {0, 0, 0, 0};
    for (int b = 0; b < 4; ++b) {
        const Vec2* c = &values_[std::size_t((s.j0 + b) * columns_ + s.i0)];
        const double u =
            s.bx[0] * c[0][0] + s.bx[1] * c[1][0] + s.bx[2] * c[2][0] + s.bx[3] * c[3][0];
        const double v =
            s.bx[0] * c[0][1] + s.bx[1] * c[1][1] + s.bx[2] * c[2][1] + s.bx[3] * c[3][1];
        delta[0] += s.by[b] * u;
        delta[1] += s.by[b] * v;
        if (!derivatives)
            continue;
        const double du =
            s.dx[0] * c[0][0] + s.dx[1] * c[1][0] + s.dx[2] * c[2][0] + s.dx[3] * c[3][0];
        const double dv =
            s.dx[0] * c[0][1] + s.dx[1] * c[1][1] + s.dx[2] * c[2][1] + s.dx[3] * c[3][1];
        J[0] += s.by[b] * du;
        J[1] += s.dy[b] * u;
        J[2] += s.by[b] * dv;
        J[3] += s.dy[b] * v;
    }
}

void CorrectionGrid::support(Vec2 pixel, int index[kSupport], double weight[kSupport]) const {
    const Basis s = basis_at(pixel, false);
    for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
            index[b * 4 + a] = (s.j0 + b) * columns_ + s.i0 + a;
            weight[b * 4 + a] = s.bx[a] * s.by[b];
        }
}

Vec2 CorrectionGrid::displacement(Vec2 pixel) const {
    if (empty())
        return {0, 0};
    Vec2 delta;
    Mat2 J;
    evaluate(basis_at(pixel, false), false, delta, J);
    return delta;
}

Mat2 CorrectionGrid::jacobian(Vec2 pixel) const {
    if (empty())
        return {0, 0, 0, 0};
    Vec2 delta;
    Mat2 J;
    evaluate(basis_at(pixel, true), true, delta, J);
    return J;
}

void CorrectionGrid::displacement_and_jacobian(Vec2 pixel, Vec2& delta, Mat2& J) const {
    if (empty()) {
        delta = {0, 0};
        J = {0, 0, 0, 0};
        return;
    }
    evaluate(basis_at(pixel, true), true, delta, J);
}

void CorrectionGrid::support_and_jacobian(Vec2 pixel, int index[kSupport], double weight[kSupport],
                                          Mat2& J) const {
    const Basis s = basis_at(pixel, true);
    for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
            index[b * 4 + a] = (s.j0 + b) * columns_ + s.i0 + a;
            weight[b * 4 + a] = s.bx[a] * s.by[b];
        }
    Vec2 delta;
    evaluate(s, true, delta, J);
}

Vec2 CorrectionGrid::apply(Vec2 model_pixel) const {
    const Vec2 d = displacement(model_pixel);
    return {model_pixel[0] + d[0], model_pixel[1] + d[1]};
}

bool CorrectionGrid::remove(Vec2 observed, Vec2& model_pixel) const {
    if (empty()) {
        model_pixel = observed;
        return true;
    }
    Vec2 p = observed;
    for (int it = 0; it < 20; ++it) {
        const Vec2 d = displacement(p);
        const double ru = p[0] + d[0] - observed[0], rv = p[1] + d[1] - observed[1];
        if (std::fabs(ru) + std::fabs(rv) <= 1e-9) {
            model_pixel = p;
            return true;
        }
        const Mat2 J = jacobian(p);
        const double a = 1 + J[0], b = J[1], c = J[2], e = 1 + J[3];
        const double det = a * e - b * c;
        if (!(det > 0.1) || !std::isfinite(det))
            return false; // the field folds the image: not a lens
        p[0] -= (e * ru - b * rv) / det;
        p[1] -= (a * rv - c * ru) / det;
    }
    return false;
}

} // namespace fpp::calib
