#pragma once
// Board poses a careful calibration session needs and a corner finder finds
// hardest: strongly tilted, pushed into the image's corners (shared by the
// corner tests and bench_corners). Header only.

#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace fpp::test {

// 15 x 11 inner corners of 12 mm on the session's white board.
inline sim::CheckerboardSpec careful_session_board() {
    sim::CheckerboardSpec spec;
    spec.inner_columns = 15;
    spec.inner_rows = 11;
    spec.square_size = 12;
    spec.margin = 120;
    return spec;
}

// Whether every point of the board's outline `extra` squares beyond its
// pattern (0.25: the quarter square of white a finder needs) maps inside the
// camera image with `margin_px` to spare (camera = true) or inside the
// projector image (camera = false: the pattern is lit).
inline bool board_outline_inside(const sim::Rig& rig, const sim::CheckerboardSpec& spec,
                                 const sim::Pose& pose, double extra, double margin_px,
                                 bool camera) {
    const double s = spec.square_size;
    const double hx = ((spec.inner_columns + 1) * 0.5 + extra) * s;
    const double hy = ((spec.inner_rows + 1) * 0.5 + extra) * s;
    const Size size = camera ? rig.camera_size : rig.projector_size;
    constexpr int kSamples = 24;
    for (int e = 0; e < 4; ++e)
        for (int k = 0; k <= kSamples; ++k) {
            const double f = -1 + 2.0 * k / kSamples;
            const Vec3 local = e == 0   ? Vec3{f * hx, -hy, 0}
                               : e == 1 ? Vec3{f * hx, hy, 0}
                               : e == 2 ? Vec3{-hx, f * hy, 0}
                                        : Vec3{hx, f * hy, 0};
            Vec3 p = pose.to_camera(local);
            if (!camera) {
                const Mat3& R = rig.R;
                p = {R[0] * p[0] + R[1] * p[1] + R[2] * p[2] + rig.t[0],
                     R[3] * p[0] + R[4] * p[1] + R[5] * p[2] + rig.t[1],
                     R[6] * p[0] + R[7] * p[1] + R[8] * p[2] + rig.t[2]};
            }
            if (!(p[2] > 1))
                return false;
            const Vec2 q = camera ? rig.camera.project(p) : rig.projector.project(p);
            if (!(q[0] >= margin_px && q[1] >= margin_px && q[0] <= size.width - 1 - margin_px &&
                  q[1] <= size.height - 1 - margin_px))
                return false;
        }
    return true;
}

struct CornerPose {
    sim::Pose pose;
    double tilt_deg = 0; // the board normal's angle to the camera's axis
};

// Boards tilted by each of `tilts_deg` about three axes in the board's plane
// (60 degrees apart), at depths from `z0_mm` in 40 mm steps, each pushed from
// the image centre towards each image corner until its pattern and a quarter
// square of white come within 12 px (scaled with the camera's width / 1600,
// at least 8) of the image's border; only those whose whole pattern the
// projector lights (`lit`), or only those it does not.
inline std::vector<CornerPose> tilted_corner_poses(const sim::Rig& rig,
                                                   const sim::CheckerboardSpec& spec,
                                                   const std::vector<double>& tilts_deg,
                                                   double z0_mm, bool lit = true) {
    constexpr double kPi = 3.14159265358979323846;
    const double margin = std::max(8.0, 12.0 * rig.camera_size.width / 1600.0);
    const double to_x = 0.35 * 0.8, to_y = 0.35 * 0.6; // shift per mm of depth at s = 1
    std::vector<CornerPose> out;
    int n = 0;
    for (const double tilt : tilts_deg)
        for (int c = 0; c < 4; ++c)
            for (int d = 0; d < 3; ++d, ++n) {
                const double sx = c % 2 == 0 ? -1 : 1, sy = c < 2 ? -1 : 1;
                const double direction = (d * 60.0 + c * 25.0 + tilt) * kPi / 180;
                const double z = z0_mm + 40.0 * (n % 4);
                const sim::Pose tilted =
                    sim::Pose::from_euler_deg({0, 0, z}, tilt * std::cos(direction),
                                              tilt * std::sin(direction), 5.0 * (n % 3 - 1));
                auto at = [&](double s) {
                    sim::Pose p = tilted;
                    p.centre = {sx * s * to_x * z, sy * s * to_y * z, z};
                    return p;
                };
                auto visible = [&](double s) {
                    return board_outline_inside(rig, spec, at(s), 0.25, margin, true);
                };
                if (!visible(0))
                    continue;
                double lo = 0, hi = 1;
                if (visible(1))
                    lo = 1;
                else
                    for (int k = 0; k < 12; ++k)
                        (visible(0.5 * (lo + hi)) ? lo : hi) = 0.5 * (lo + hi);
                const sim::Pose pose = at(0.97 * lo);
                if (board_outline_inside(rig, spec, pose, 0.0, 2.0, false) == lit)
                    out.push_back({pose, std::acos(std::fabs(pose.R[8])) * 180 / kPi});
            }
    return out;
}

// The white frame of a board pose (8-bit camera DN as floats).
inline Image<float> white_frame(const sim::Rig& rig, const sim::Scene& scene, std::uint64_t seed) {
    const sim::Renderer renderer(rig, scene);
    const Frame frame = renderer.render(Image<std::uint8_t>(rig.projector_size, 1, 255), seed);
    Image<float> out(frame.size());
    for (std::size_t i = 0; i < out.pixel_count(); ++i)
        out.data()[i] = static_cast<float>(frame.u8.data()[i]);
    return out;
}

} // namespace fpp::test
