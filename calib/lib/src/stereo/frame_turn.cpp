// The turn between a calibrated and a true camera frame (see
// fpp/calib/frame_turn.hpp).

#include "fpp/calib/frame_turn.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fpp::calib {

namespace {

Eigen::Vector3d unit_ray(const Vec2& n) {
    return Eigen::Vector3d(n[0], n[1], 1).normalized();
}

} // namespace

FrameTurn camera_frame_turn(const StereoCalibration& calibration, const LensModel& true_camera,
                            int step_px) {
    if (step_px < 1)
        throw std::invalid_argument("camera frame turn: step_px must be at least 1");
    const Size size = calibration.camera_size;
    std::vector<Eigen::Vector3d> from, to;
    for (int v = 0; v < size.height; v += step_px)
        for (int u = 0; u < size.width; u += step_px) {
            Vec2 a{}, b{};
            if (!calibration.camera_ray({double(u), double(v)}, a) ||
                !true_camera.pixel_to_normalised({double(u), double(v)}, b))
                continue;
            from.push_back(unit_ray(a));
            to.push_back(unit_ray(b));
        }
    if (from.size() < 3)
        throw std::invalid_argument("camera frame turn: fewer than 3 pixels with both rays");
    // Kabsch: Q = argmin sum |Q a - b|^2 over rotations, from the SVD of
    // sum a b^T, its sign fixed so that Q is proper.
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    for (std::size_t k = 0; k < from.size(); ++k)
        H += from[k] * to[k].transpose();
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
    const Eigen::Matrix3d Q = svd.matrixV() * D * svd.matrixU().transpose();

    FrameTurn turn;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            turn.Q[std::size_t(3 * r + c)] = Q(r, c);
    turn.angle_rad = std::acos(std::clamp((Q.trace() - 1) / 2, -1.0, 1.0));
    double sum = 0;
    for (std::size_t k = 0; k < from.size(); ++k) {
        const Eigen::Vector3d a = Q * from[k];
        sum += std::pow(std::atan2(a.cross(to[k]).norm(), a.dot(to[k])), 2);
    }
    turn.ray_rms_rad = std::sqrt(sum / double(from.size()));
    turn.rays = int(from.size());
    return turn;
}

void turn_points(const FrameTurn& turn, std::vector<Vec3>& points) {
    for (Vec3& p : points)
        p = mul(turn.Q, p);
}

} // namespace fpp::calib
