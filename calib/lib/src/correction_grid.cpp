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
    first = std::clamp(static_cast<int>(std::floor(s)), 0, intervals - 1);
    f = s - first; // outside [0, 1] beyond the image: the edge polynomial continues
}

void CorrectionGrid::support(Vec2 pixel, int index[kSupport], double weight[kSupport]) const {
    int i0, j0;
    double fx, fy;
    locate(pixel[0], spacing_x_, columns_ - 3, i0, fx);
    locate(pixel[1], spacing_y_, rows_ - 3, j0, fy);
    double bx[4], by[4];
    basis(fx, bx);
    basis(fy, by);
    for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
            index[b * 4 + a] = (j0 + b) * columns_ + i0 + a;
            weight[b * 4 + a] = bx[a] * by[b];
        }
}

Vec2 CorrectionGrid::displacement(Vec2 pixel) const {
    if (empty())
        return {0, 0};
    int index[kSupport];
    double weight[kSupport];
    support(pixel, index, weight);
    Vec2 d{0, 0};
    for (int k = 0; k < kSupport; ++k) {
        const Vec2& c = values_[std::size_t(index[k])];
        d[0] += weight[k] * c[0];
        d[1] += weight[k] * c[1];
    }
    return d;
}

// The spline's basis at a pixel: first control point and the weights
// along each axis, and their derivatives per pixel.
struct CorrectionGrid::Basis {
    int i0 = 0, j0 = 0;
    double bx[4], by[4], dx[4], dy[4];
};

CorrectionGrid::Basis CorrectionGrid::basis_at(Vec2 pixel) const {
    Basis b;
    double fx, fy;
    locate(pixel[0], spacing_x_, columns_ - 3, b.i0, fx);
    locate(pixel[1], spacing_y_, rows_ - 3, b.j0, fy);
    basis(fx, b.bx);
    basis(fy, b.by);
    basis_derivative(fx, b.dx);
    basis_derivative(fy, b.dy);
    return b;
}

Mat2 CorrectionGrid::jacobian(Vec2 pixel) const {
    if (empty())
        return {0, 0, 0, 0};
    Vec2 delta;
    Mat2 J;
    displacement_and_jacobian(pixel, delta, J);
    return J;
}

void CorrectionGrid::displacement_and_jacobian(Vec2 pixel, Vec2& delta, Mat2& J) const {
    delta = {0, 0};
    J = {0, 0, 0, 0};
    if (empty())
        return;
    const Basis s = basis_at(pixel);
    for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
            const Vec2& c = values_[std::size_t((s.j0 + b) * columns_ + s.i0 + a)];
            const double w = s.bx[a] * s.by[b];
            delta[0] += w * c[0];
            delta[1] += w * c[1];
            const double wu = s.dx[a] * s.by[b] / spacing_x_, wv = s.bx[a] * s.dy[b] / spacing_y_;
            J[0] += wu * c[0];
            J[1] += wv * c[0];
            J[2] += wu * c[1];
            J[3] += wv * c[1];
        }
}

void CorrectionGrid::support_and_jacobian(Vec2 pixel, int index[kSupport],
                                          double weight[kSupport], Mat2& J) const {
    J = {0, 0, 0, 0};
    const Basis s = basis_at(pixel);
    for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
            const int k = (s.j0 + b) * columns_ + s.i0 + a;
            index[b * 4 + a] = k;
            weight[b * 4 + a] = s.bx[a] * s.by[b];
            const Vec2& c = values_[std::size_t(k)];
            const double wu = s.dx[a] * s.by[b] / spacing_x_, wv = s.bx[a] * s.dy[b] / spacing_y_;
            J[0] += wu * c[0];
            J[1] += wv * c[0];
            J[2] += wu * c[1];
            J[3] += wv * c[1];
        }
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
