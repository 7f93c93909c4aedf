#pragma once
// Synthetic stereo-calibration sessions: a simulated rig's checkerboard
// corners projected through its exact model, with Gaussian noise of a known
// sigma, so that a calibration can be compared with the truth.

#include "fpp/calib/stereo_calibrate.hpp"
#include "fpp/calib/stereo_session.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/session.hpp"

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace fpp::test {

// The paper rig without the terms outside the calibrated model.
inline sim::Rig model_rig() {
    sim::Rig rig = sim::Rig::paper();
    rig.camera.drop_unmodelled_terms();
    rig.projector.drop_unmodelled_terms();
    return rig;
}

// Camera-frame points (mm) seen by both devices of `rig`, each coordinate
// plus jitter() (camera u, v, then projector u, v, point by point).
template <class Jitter>
void see_points(const sim::Rig& rig, const std::vector<Vec3>& points, Jitter&& jitter,
                calib::PoseObservations& o) {
    for (const Vec3& x : points) {
        const Vec2 c = rig.camera.project(x);
        const Vec3 xp = mul(rig.R, x);
        const Vec2 q =
            rig.projector.project({xp[0] + rig.t[0], xp[1] + rig.t[1], xp[2] + rig.t[2]});
        o.camera.push_back({c[0] + jitter(), c[1] + jitter()});
        o.projector.push_back({q[0] + jitter(), q[1] + jitter()});
    }
}

// The session's 11 x 8 board at the poses `session` draws for `rig`, seen by
// both devices; `noise_px` Gaussian noise (seeded by `noise_seed`) on every
// coordinate.
inline std::vector<calib::PoseObservations> observe(const sim::Rig& rig,
                                                    const sim::SessionOptions& session,
                                                    double noise_px, std::uint32_t noise_seed) {
    const std::vector<sim::Pose> board_poses = sim::session_poses(rig, session);
    const sim::CheckerboardSpec& spec = session.board;
    const std::vector<Vec3> board =
        calib::checkerboard_points(spec.inner_columns, spec.inner_rows, spec.square_size);
    std::mt19937 rng(noise_seed);
    std::normal_distribution<double> noise(0.0, noise_px);
    const auto jitter = [&]() { return noise_px > 0 ? noise(rng) : 0.0; };
    std::vector<calib::PoseObservations> out;
    for (std::size_t p = 0; p < board_poses.size(); ++p) {
        // Board frame of the calibration: origin at inner corner (0, 0).
        const sim::Checkerboard cb(board_poses[p], spec);
        calib::PoseObservations o;
        o.name = "pose-" + std::to_string(p + 1);
        o.board = board;
        see_points(rig, cb.inner_corners(), jitter, o);
        out.push_back(std::move(o));
    }
    return out;
}

// The board at pose X = R X_b + t (camera frame, mm; board frame as
// checkerboard_points) seen by both devices of `rig`, with noise.
inline calib::PoseObservations observe_pose(const sim::Rig& rig, const Mat3& R, const Vec3& t,
                                            const std::vector<Vec3>& board, double noise_px,
                                            std::mt19937& rng, const std::string& name) {
    std::normal_distribution<double> noise(0.0, noise_px);
    const auto jitter = [&]() { return noise_px > 0 ? noise(rng) : 0.0; };
    calib::PoseObservations o;
    o.name = name;
    o.board = board;
    std::vector<Vec3> points;
    for (const Vec3& b : board) {
        const Vec3 rb = mul(R, b);
        points.push_back({rb[0] + t[0], rb[1] + t[1], rb[2] + t[2]});
    }
    see_points(rig, points, jitter, o);
    return o;
}

inline std::vector<calib::PoseObservations> observe(const sim::Rig& rig, int poses, double noise_px,
                                                    std::uint32_t seed = 3) {
    sim::SessionOptions session;
    session.poses = poses;
    return observe(rig, session, noise_px, seed);
}

} // namespace fpp::test
