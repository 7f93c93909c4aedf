// The small vector arithmetic (fpp/vec3.hpp) that the simulator and the
// calibration share: each operation on values whose results are exact.

#include "fpp/vec3.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using fpp::Mat3;
using fpp::Vec3;
namespace vec = fpp::vec;

TEST(Vec3, AddSubtractScaleAreElementWise) {
    const Vec3 a{1, -2, 3.5}, b{0.5, 4, -1};
    EXPECT_EQ(vec::add(a, b), (Vec3{1.5, 2, 2.5}));
    EXPECT_EQ(vec::sub(a, b), (Vec3{0.5, -6, 4.5}));
    EXPECT_EQ(vec::scale(a, -2), (Vec3{-2, 4, -7}));
}

TEST(Vec3, DotCrossAndNorm) {
    const Vec3 a{1, 2, 3}, b{4, -5, 6};
    EXPECT_EQ(vec::dot(a, b), 12.0); // 4 - 10 + 18
    EXPECT_EQ(vec::cross(a, b), (Vec3{27, 6, -13}));
    // The cross product is perpendicular to both and anti-commutes.
    EXPECT_EQ(vec::dot(vec::cross(a, b), a), 0.0);
    EXPECT_EQ(vec::dot(vec::cross(a, b), b), 0.0);
    EXPECT_EQ(vec::cross(b, a), vec::scale(vec::cross(a, b), -1));
    // Right-handed: x cross y = z.
    EXPECT_EQ(vec::cross(Vec3{1, 0, 0}, Vec3{0, 1, 0}), (Vec3{0, 0, 1}));
    EXPECT_EQ(vec::norm(Vec3{3, 4, 12}), 13.0);
    EXPECT_EQ(vec::norm(Vec3{0, 0, 0}), 0.0);
}

TEST(Vec3, NormalisedHasUnitLengthAndTheSameDirection) {
    const Vec3 n = vec::normalised(Vec3{0, -3, 4});
    EXPECT_DOUBLE_EQ(n[0], 0.0);
    EXPECT_DOUBLE_EQ(n[1], -0.6);
    EXPECT_DOUBLE_EQ(n[2], 0.8);
    EXPECT_DOUBLE_EQ(vec::norm(vec::normalised(Vec3{1e-3, 2e-3, -7e-3})), 1.0);
    // A zero vector has no direction: NaN, not a made-up one.
    const Vec3 zero = vec::normalised(Vec3{0, 0, 0});
    EXPECT_TRUE(std::isnan(zero[0]) && std::isnan(zero[1]) && std::isnan(zero[2]));
}

TEST(Vec3, ColumnOfARowMajorMatrix) {
    const Mat3 m{1, 2, 3, 4, 5, 6, 7, 8, 9};
    EXPECT_EQ(vec::column(m, 0), (Vec3{1, 4, 7}));
    EXPECT_EQ(vec::column(m, 1), (Vec3{2, 5, 8}));
    EXPECT_EQ(vec::column(m, 2), (Vec3{3, 6, 9}));
}

} // namespace
