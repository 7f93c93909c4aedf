#pragma once
// A dense correction of a device's lens model: a smooth displacement field
// over its image, in pixels, that absorbs lens defects no parametric model
// has (a tilted or decentred element, a stressed mount, moulding errors).
//
//   observed pixel = model pixel + delta(model pixel)
//
// where "model pixel" is fpp::LensModel's projection and delta is a uniform
// bicubic B-spline over the image: `columns` x `rows` control points, each a
// displacement (du, dv) in pixels, spanning [-0.5, width - 0.5] x [-0.5,
// height - 0.5] with (columns - 3) x (rows - 3) spline intervals. Pixel
// centres on integers. Outside the image the edge intervals' polynomials
// continue (a point a little outside the projector image still projects).
//
// A correction grid is estimated together with its lens model by the bundle
// adjustment (stereo_calibrate.hpp), which regularises it (smoothness, and a
// small pull towards zero, so that what the parametric model can express
// stays in the parametric model).

#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <vector>

namespace fpp::calib {

class CorrectionGrid {
public:
    static constexpr int kSupport = 16; // control points that move one pixel

    CorrectionGrid() = default; // empty: no correction
    // A zero field of columns x rows control points (each at least 4) over
    // an image of `image` pixels. Throws std::invalid_argument otherwise.
    CorrectionGrid(Size image, int columns, int rows);

    bool empty() const { return columns_ == 0; }
    Size image() const { return image_; }
    int columns() const { return columns_; }
    int rows() const { return rows_; }
    int control_points() const { return columns_ * rows_; }
    // Control point (i, j), i < columns, j < rows: its displacement (px).
    Vec2& at(int i, int j) { return values_[std::size_t(j * columns_ + i)]; }
    const Vec2& at(int i, int j) const { return values_[std::size_t(j * columns_ + i)]; }
    // All control points, row-major (index j * columns + i).
    std::vector<Vec2>& values() { return values_; }
    const std::vector<Vec2>& values() const { return values_; }
    // Largest |displacement| over the control points (px); 0 when empty.
    double largest_control_value() const;

    // The control points that move `pixel` (row-major indices) and their
    // B-spline weights (summing to 1). Empty grid: nothing to do.
    void support(Vec2 pixel, int index[kSupport], double weight[kSupport]) const;
    // delta(pixel); {0, 0} when empty.
    Vec2 displacement(Vec2 pixel) const;
    // d delta / d pixel, row-major [ddu/du, ddu/dv, ddv/du, ddv/dv].
    Mat2 jacobian(Vec2 pixel) const;
    // displacement() and jacobian() at once, to the same values (the
    // spline is located once); zeros when empty.
    void displacement_and_jacobian(Vec2 pixel, Vec2& delta, Mat2& J) const;
    // support() and jacobian() at once, to the same values.
    void support_and_jacobian(Vec2 pixel, int index[kSupport], double weight[kSupport],
                              Mat2& J) const;
    // model pixel -> observed pixel.
    Vec2 apply(Vec2 model_pixel) const;
    // observed pixel -> model pixel, by Newton iterations (the field bends
    // the image by far less than a pixel per pixel). Returns false if it does
    // not converge to 1e-9 px.
    bool remove(Vec2 observed, Vec2& model_pixel) const;

private:
    // Spline coordinates of a pixel: first control point index and the
    // fraction within the interval, per axis.
    void locate(double pixel, double spacing, int intervals, int& first, double& f) const;
    struct Basis;
    Basis basis_at(Vec2 pixel, bool derivatives) const;
    void evaluate(const Basis& basis, bool derivatives, Vec2& delta, Mat2& J) const;

    Size image_;
    int columns_ = 0, rows_ = 0;
    double spacing_x_ = 1, spacing_y_ = 1; // px per interval
    std::vector<Vec2> values_;
};

// Second-difference smoothness of a grid's field, one term per (triple of
// neighbouring control points along a row or a column, and mixed square):
// calls term(indices, coefficients, count) with count control points whose
// combination sum c_k value_k is one second difference. Used to regularise
// the bundle adjustment.
template <class F> void for_each_smoothness_term(int columns, int rows, F&& term) {
    for (int j = 0; j < rows; ++j)
        for (int i = 1; i + 1 < columns; ++i) {
            const int idx[3] = {j * columns + i - 1, j * columns + i, j * columns + i + 1};
            const double c[3] = {1, -2, 1};
            term(idx, c, 3);
        }
    for (int j = 1; j + 1 < rows; ++j)
        for (int i = 0; i < columns; ++i) {
            const int idx[3] = {(j - 1) * columns + i, j * columns + i, (j + 1) * columns + i};
            const double c[3] = {1, -2, 1};
            term(idx, c, 3);
        }
    // Mixed second differences, weighted sqrt(2) (thin-plate energy).
    constexpr double m = 1.4142135623730951;
    for (int j = 0; j + 1 < rows; ++j)
        for (int i = 0; i + 1 < columns; ++i) {
            const int idx[4] = {j * columns + i, j * columns + i + 1, (j + 1) * columns + i,
                                (j + 1) * columns + i + 1};
            const double c[4] = {m, -m, -m, m};
            term(idx, c, 4);
        }
}

} // namespace fpp::calib
