#pragma once
// Small fixed-size vectors and 3 x 3 matrices (row-major) of doubles, and the
// 3-vector arithmetic the simulator and the calibration share. Frames and
// units are the caller's (camera frame, mm, everywhere in fpp).
#include <array>
#include <cmath>

namespace fpp {

using Vec2 = std::array<double, 2>;
using Vec3 = std::array<double, 3>;
using Mat3 = std::array<double, 9>; // row-major
using Mat2 = std::array<double, 4>; // row-major

namespace vec {

inline Vec3 add(const Vec3& a, const Vec3& b) {
    return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
inline Vec3 sub(const Vec3& a, const Vec3& b) {
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
inline Vec3 scale(const Vec3& a, double s) {
    return {a[0] * s, a[1] * s, a[2] * s};
}
inline double dot(const Vec3& a, const Vec3& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Vec3& a) {
    return std::sqrt(dot(a, a));
}
inline Vec3 normalised(const Vec3& a) {
    return scale(a, 1.0 / norm(a));
}
// Column j of a row-major 3x3 matrix.
inline Vec3 column(const Mat3& m, int j) {
    return {m[j], m[3 + j], m[6 + j]};
}

} // namespace vec

} // namespace fpp
