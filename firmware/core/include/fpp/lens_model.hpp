#pragma once
// Pinhole camera with skew and Brown-Conrady distortion (OpenCV's formula,
// the paper's eq. 3), used for the camera and for the projector (an inverse
// camera).
//
//   normalised:  (xn, yn) = (X/Z, Y/Z) in the device's own frame (mm)
//   distorted:   r2 = xn^2 + yn^2
//                xd = xn (1 + k1 r2 + k2 r2^2 + k3 r2^3 + k4 r2^4) + 2 p1 xn yn + p2 (r2 + 2 xn^2)
//                     + s1 r2 + s2 r2^2
//                yd = yn (1 + k1 r2 + k2 r2^2 + k3 r2^3 + k4 r2^4) + p1 (r2 + 2 yn^2) + 2 p2 xn yn
//                     + s3 r2 + s4 r2^2
//                plus the trefoil term (t1 + i t2) conj(xn + i yn)^2:
//                xd += t1 (xn^2 - yn^2) + 2 t2 xn yn,  yd += t2 (xn^2 - yn^2) - 2 t1 xn yn
//                plus the decentred element, a radial distortion about (dc_x, dc_y)
//                (normalised) instead of the optical axis:
//                dx = xn - dc_x,  dy = yn - dc_y,  rho2 = dx^2 + dy^2,
//                g(rho2) = dc_k1 rho2 + dc_k2 rho2^2,  g0 = g(dc_x^2 + dc_y^2)
//                xd += dx g(rho2) + dc_x g0,  yd += dy g(rho2) + dc_y g0
//                (the term minus its value at xn = yn = 0, so the axis stays put)
//   pixel:       u = fu xd + skew yd + cu,  v = fv yd + cv   (pixel centres on integers)
//
// k4 (8th-order radial), s1..s4 (thin prism), t1, t2 (three-lobed, as
// element tilt and mounting stress leave it) and the decentred element
// (dc_k1, dc_k2 about dc_x, dc_y: an element mounted off the axis) are not
// part of the calibrated model (OpenCV's 5-coefficient model); the simulator
// uses them to create distortion that a stereo calibration cannot represent.
// Of the six quadratic distortion fields, the tangential and prism terms span
// four; the trefoil term is the other two, a shape no term of OpenCV's 5- to
// 14-coefficient models has. The decentred element's dc_k1 part alone is,
// to first order in dc_k1, within the model: expanded about the axis it is
// k1 = dc_k1, tangential p1 = -dc_k1 dc_y, p2 = -dc_k1 dc_x, and a linear map
// that focal lengths, skew and the extrinsics absorb. Its dc_k2 part with a
// non-zero centre is not: it leaves fourth-order decentring and cubic
// non-radial terms that no term of the model has.
//
// Rotations: R = Rz(c) Ry(b) Rx(a) for Euler angles (a, b, c) in degrees, i.e.
// rotate about x first, then y, then z (fixed axes). X_p = R X_c + t.

#include "fpp/vec3.hpp"

namespace fpp {

struct LensModel {
    double fu = 1, fv = 1, cu = 0, cv = 0, skew = 0;
    double k1 = 0, k2 = 0, k3 = 0, p1 = 0, p2 = 0;
    double k4 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0; // outside the calibrated model
    double t1 = 0, t2 = 0;                         // outside the calibrated model
    // Decentred element (outside the calibrated model): radial coefficients
    // and its centre, normalised coordinates.
    double dc_k1 = 0, dc_k2 = 0, dc_x = 0, dc_y = 0;

    // Whether any term outside the calibrated model is non-zero (the
    // decentred element's centre alone is no term: it needs dc_k1 or dc_k2).
    bool has_unmodelled_terms() const;
    // Sets the terms outside the calibrated model to zero.
    void drop_unmodelled_terms();
    // Normalised undistorted -> normalised distorted.
    Vec2 distort(Vec2 n) const;
    // d(distorted)/d(undistorted) at n, row-major [dxd/dxn, dxd/dyn, dyd/dxn, dyd/dyn].
    Mat2 distortion_jacobian(Vec2 n) const;
    // Normalised distorted <-> pixel (the linear part only).
    Vec2 distorted_to_pixel(Vec2 d) const;
    Vec2 pixel_to_distorted(Vec2 pixel) const;
    // Inverse of distort, by Newton iterations to ~1e-12; returns false if it
    // does not converge (far outside the lens's valid field).
    bool undistort(Vec2 d, Vec2& n) const;
    // Point in the device frame (mm, Z > 0) -> pixel.
    Vec2 project(const Vec3& p) const;
    // Pixel -> normalised undistorted coordinates (the ray is (x, y, 1)).
    bool pixel_to_normalised(Vec2 pixel, Vec2& n) const;
};

// Rotation from Euler angles in degrees, R = Rz(c) * Ry(b) * Rx(a).
Mat3 rotation_from_euler_deg(double a, double b, double c);
Vec3 mul(const Mat3& m, const Vec3& v);
Mat3 transpose(const Mat3& m);
Mat3 mul(const Mat3& a, const Mat3& b);

} // namespace fpp
