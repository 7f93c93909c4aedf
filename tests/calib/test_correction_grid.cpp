// The dense lens correction (fpp/calib/correction_grid.hpp): a uniform
// bicubic B-spline of displacements. Its weights sum to one, it reproduces
// constant and linear fields exactly (inside the image and a little beyond),
// a control point moves only the pixels of its support, the Jacobian and
// the inverse (remove) agree with the field, a folding field is refused, and
// the smoothness terms vanish on linear fields.

#include "fpp/calib/correction_grid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

using fpp::Mat2;
using fpp::Size;
using fpp::Vec2;
using fpp::calib::CorrectionGrid;

namespace {

// 64 x 48 pixels, 7 x 6 control points: intervals of 16 px on both axes.
constexpr Size kImage{64, 48};

// A grid whose field is du = a.x + b, dv = c.x + d.y: cubic B-splines
// reproduce a linear function when control point k holds its value at the
// spline coordinate k - 1, pixel (k - 1) spacing - 0.5.
CorrectionGrid linear_grid(double a, double b, double c, double d) {
    CorrectionGrid g(kImage, 7, 6);
    for (int j = 0; j < g.rows(); ++j)
        for (int i = 0; i < g.columns(); ++i) {
            const double x = (i - 1) * 16.0 - 0.5, y = (j - 1) * 16.0 - 0.5;
            g.at(i, j) = {a * x + b, c * x + d * y};
        }
    return g;
}

const Vec2 kPixels[] = {{0, 0},       {63, 47}, {31.5, 20.25}, {-0.5, -0.5},
                        {63.5, 47.5}, {17, 3},  {-3, 50},      {70, -4}};

TEST(CorrectionGrid, RefusesTooFewControlPointsOrNoImage) {
    const auto message = [](Size image, int columns, int rows) -> std::string {
        try {
            CorrectionGrid g(image, columns, rows);
        } catch (const std::invalid_argument& e) {
            return e.what();
        }
        return "accepted";
    };
    EXPECT_EQ(message(kImage, 3, 4), "correction grid: at least 4 x 4 control points, got 3 x 4");
    EXPECT_EQ(message(kImage, 4, 2), "correction grid: at least 4 x 4 control points, got 4 x 2");
    EXPECT_EQ(message({1, 48}, 4, 4), "correction grid: image size must be positive");
    EXPECT_EQ(message(kImage, 4, 4), "accepted");
}

TEST(CorrectionGrid, AnEmptyGridCorrectsNothing) {
    const CorrectionGrid none;
    EXPECT_TRUE(none.empty());
    EXPECT_EQ(none.control_points(), 0);
    EXPECT_EQ(none.largest_control_value(), 0.0);
    EXPECT_EQ(none.displacement({12, 7}), (Vec2{0, 0}));
    EXPECT_EQ(none.jacobian({12, 7}), (Mat2{0, 0, 0, 0}));
    EXPECT_EQ(none.apply({12.25, 7.5}), (Vec2{12.25, 7.5}));
    Vec2 model;
    EXPECT_TRUE(none.remove({12.25, 7.5}, model));
    EXPECT_EQ(model, (Vec2{12.25, 7.5}));
}

TEST(CorrectionGrid, ShapeAndControlPoints) {
    CorrectionGrid g(kImage, 7, 6);
    EXPECT_FALSE(g.empty());
    EXPECT_EQ(g.image(), kImage);
    EXPECT_EQ(g.columns(), 7);
    EXPECT_EQ(g.rows(), 6);
    EXPECT_EQ(g.control_points(), 42);
    EXPECT_EQ(g.largest_control_value(), 0.0); // a zero field
    g.at(2, 3) = {3, -4};
    EXPECT_EQ(g.values()[3 * 7 + 2], (Vec2{3, -4})); // row-major
    EXPECT_EQ(g.largest_control_value(), 5.0);
}

TEST(CorrectionGrid, WeightsOfSixteenDistinctControlPointsSumToOne) {
    const CorrectionGrid g(kImage, 7, 6);
    for (const Vec2& p : kPixels) {
        int index[CorrectionGrid::kSupport];
        double weight[CorrectionGrid::kSupport];
        g.support(p, index, weight);
        double sum = 0;
        std::set<int> distinct;
        for (int k = 0; k < CorrectionGrid::kSupport; ++k) {
            sum += weight[k];
            distinct.insert(index[k]);
            EXPECT_GE(index[k], 0);
            EXPECT_LT(index[k], g.control_points());
        }
        EXPECT_NEAR(sum, 1.0, 1e-12) << p[0] << ", " << p[1];
        EXPECT_EQ(distinct.size(), 16u);
    }
}

TEST(CorrectionGrid, ReproducesConstantAndLinearFields) {
    const CorrectionGrid constant = linear_grid(0, 2.5, 0, 0);
    const CorrectionGrid linear = linear_grid(0.01, 0.5, 0.03, -0.02);
    for (const Vec2& p : kPixels) {
        const Vec2 c = constant.displacement(p);
        EXPECT_NEAR(c[0], 2.5, 1e-12);
        EXPECT_NEAR(c[1], 0.0, 1e-12);
        const Vec2 d = linear.displacement(p);
        EXPECT_NEAR(d[0], 0.01 * p[0] + 0.5, 1e-12) << p[0] << ", " << p[1];
        EXPECT_NEAR(d[1], 0.03 * p[0] - 0.02 * p[1], 1e-12) << p[0] << ", " << p[1];
        const Mat2 J = linear.jacobian(p);
        EXPECT_NEAR(J[0], 0.01, 1e-12);
        EXPECT_NEAR(J[1], 0.0, 1e-12);
        EXPECT_NEAR(J[2], 0.03, 1e-12);
        EXPECT_NEAR(J[3], -0.02, 1e-12);
        const Vec2 moved = linear.apply(p);
        EXPECT_NEAR(moved[0], p[0] + d[0], 1e-12);
        EXPECT_NEAR(moved[1], p[1] + d[1], 1e-12);
    }
}

TEST(CorrectionGrid, AControlPointMovesOnlyThePixelsOfItsSupport) {
    CorrectionGrid g(kImage, 7, 6);
    g.at(0, 0) = {1, 1}; // the corner's: spline intervals 0 only, on both axes
    // Its weight b0(fx) b0(fy), b0(f) = (1 - f)^3 / 6, f = (pixel + 0.5) / 16.
    const auto b0 = [](double f) { return (1 - f) * (1 - f) * (1 - f) / 6; };
    EXPECT_NEAR(g.displacement({0, 0})[0], b0(0.03125) * b0(0.03125), 1e-15);
    EXPECT_NEAR(g.displacement({8, 2})[1], b0(0.53125) * b0(0.15625), 1e-15);
    EXPECT_EQ(g.displacement({15.5, 0}), (Vec2{0, 0})); // interval 1 along x
    EXPECT_EQ(g.displacement({0, 15.5}), (Vec2{0, 0}));
    EXPECT_EQ(g.displacement({40, 30}), (Vec2{0, 0}));
}

TEST(CorrectionGrid, JacobianIsTheFieldsDerivative) {
    CorrectionGrid g(kImage, 7, 6);
    for (int j = 0; j < g.rows(); ++j)
        for (int i = 0; i < g.columns(); ++i)
            g.at(i, j) = {0.3 * std::sin(i + 2.0 * j), 0.2 * std::cos(3.0 * i - j)};
    const double h = 1e-5;
    for (const Vec2& p : kPixels) {
        const Mat2 J = g.jacobian(p);
        const Vec2 xp = g.displacement({p[0] + h, p[1]}), xm = g.displacement({p[0] - h, p[1]});
        const Vec2 yp = g.displacement({p[0], p[1] + h}), ym = g.displacement({p[0], p[1] - h});
        EXPECT_NEAR(J[0], (xp[0] - xm[0]) / (2 * h), 1e-7) << p[0] << ", " << p[1];
        EXPECT_NEAR(J[1], (yp[0] - ym[0]) / (2 * h), 1e-7) << p[0] << ", " << p[1];
        EXPECT_NEAR(J[2], (xp[1] - xm[1]) / (2 * h), 1e-7) << p[0] << ", " << p[1];
        EXPECT_NEAR(J[3], (yp[1] - ym[1]) / (2 * h), 1e-7) << p[0] << ", " << p[1];
        // The combined forms give the same values.
        Vec2 delta;
        Mat2 both;
        g.displacement_and_jacobian(p, delta, both);
        EXPECT_EQ(delta, g.displacement(p));
        EXPECT_EQ(both, J);
        int index[CorrectionGrid::kSupport], index2[CorrectionGrid::kSupport];
        double weight[CorrectionGrid::kSupport], weight2[CorrectionGrid::kSupport];
        Mat2 J2;
        g.support(p, index, weight);
        g.support_and_jacobian(p, index2, weight2, J2);
        EXPECT_EQ(J2, J);
        for (int k = 0; k < CorrectionGrid::kSupport; ++k) {
            EXPECT_EQ(index2[k], index[k]);
            EXPECT_EQ(weight2[k], weight[k]);
        }
    }
}

TEST(CorrectionGrid, RemoveUndoesApply) {
    CorrectionGrid g(kImage, 7, 6);
    for (int j = 0; j < g.rows(); ++j)
        for (int i = 0; i < g.columns(); ++i)
            g.at(i, j) = {0.8 * std::sin(i + 2.0 * j), -0.6 * std::cos(3.0 * i - j)};
    for (const Vec2& p : kPixels) {
        Vec2 model{-1, -1};
        ASSERT_TRUE(g.remove(g.apply(p), model)) << p[0] << ", " << p[1];
        EXPECT_NEAR(model[0], p[0], 1e-8);
        EXPECT_NEAR(model[1], p[1], 1e-8);
    }
}

TEST(CorrectionGrid, AFieldThatFoldsTheImageCannotBeRemoved) {
    // du = -1.5 x: observed u = -0.5 x, the image turned over.
    const CorrectionGrid folding = linear_grid(-1.5, 0, 0, 0);
    Vec2 model;
    EXPECT_FALSE(folding.remove({10, 10}, model));
}

TEST(CorrectionGrid, SmoothnessTermsAreSecondDifferencesThatVanishOnLinearFields) {
    const CorrectionGrid linear = linear_grid(0.01, 0.5, 0.03, -0.02);
    int terms = 0, mixed = 0;
    fpp::calib::for_each_smoothness_term(7, 6, [&](const int* idx, const double* c, int count) {
        ++terms;
        mixed += count == 4 ? 1 : 0;
        double sum = 0, u = 0, v = 0;
        for (int k = 0; k < count; ++k) {
            sum += c[k];
            u += c[k] * linear.values()[std::size_t(idx[k])][0];
            v += c[k] * linear.values()[std::size_t(idx[k])][1];
        }
        EXPECT_NEAR(sum, 0.0, 1e-15);
        EXPECT_NEAR(u, 0.0, 1e-12);
        EXPECT_NEAR(v, 0.0, 1e-12);
    });
    // Along rows 6 x 5, along columns 4 x 7, mixed 5 x 6.
    EXPECT_EQ(terms, 30 + 28 + 30);
    EXPECT_EQ(mixed, 30);
}

} // namespace
