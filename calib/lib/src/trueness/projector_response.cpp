// How the projector stage's gradient moves with the camera stage's
// parameters (see calibration_covariance.hpp): analytically, and by
// central differences for the tests.

#include "trueness/calibration_covariance.hpp"

#include <cmath>

namespace fpp::calib::detail {

namespace {

using vec::cross;
using vec::dot;

// One derivative of a residual pair: its column in a stage, d r_u, d r_v.
struct Entry {
    int column;
    double du, dv;
};

} // namespace

Eigen::MatrixXd projector_response(const RigState& s, const std::vector<CornerObservation>& corners,
                                   const std::vector<DenseObservation>& dense,
                                   const std::vector<bool>& pose_used,
                                   const std::vector<int>& camera_index,
                                   const std::vector<int>& projector_index,
                                   const FreeParameters& projector_stage) {
    const FullOrder order = full_order(s);
    std::vector<int> col1(std::size_t(order.size), -1), col2(std::size_t(order.size), -1);
    for (std::size_t c = 0; c < camera_index.size(); ++c)
        col1[std::size_t(camera_index[c])] = int(c);
    for (std::size_t c = 0; c < projector_index.size(); ++c)
        col2[std::size_t(projector_index[c])] = int(c);
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(Eigen::Index(projector_index.size()),
                                              Eigen::Index(camera_index.size()));

    // The projector's corners move with the poses: the cross block of the
    // normal equations with both held free (no regularisation: it has no
    // cross terms).
    FreeParameters both = projector_stage;
    both.poses = true;
    const NormalEquations n =
        normal_equations(s, corners, {}, pose_used, both, GridRegularisation{0, 0, 0});
    for (std::size_t a = 0; a < n.full_index.size(); ++a)
        for (std::size_t b = 0; b < n.full_index.size(); ++b) {
            const int r = col2[std::size_t(n.full_index[a])];
            const int c = col1[std::size_t(n.full_index[b])];
            if (r >= 0 && c >= 0 && n.full_index[b] >= order.poses)
                M(r, c) += n.A(Eigen::Index(a), Eigen::Index(b));
        }

    // The dense samples move with the camera's rays and the boards' planes:
    // X = z m, m = (xn, yn, 1) the ray of the sample's pixel, z = d / (N . m)
    // on the plane N . X = d of its pose; d m from the camera's projection
    // held at the pixel (d pixel / d m dm = -d pixel / d theta).
    std::vector<Entry> moved, projector;
    for (const DenseObservation& o : dense) {
        if (o.pose < 0 || !pose_used[std::size_t(o.pose)] || !(o.camera_point[2] > 0))
            continue;
        const double z = o.camera_point[2];
        const Vec3 m{o.camera_point[0] / z, o.camera_point[1] / z, 1};
        Projection pc, pp;
        if (!project_with_derivatives(s.camera, s.camera_grid, m, pc))
            continue;
        const Vec3 rotated = mul(s.R, o.camera_point);
        if (!project_with_derivatives(
                s.projector, s.projector_grid,
                {rotated[0] + s.T[0], rotated[1] + s.T[1], rotated[2] + s.T[2]}, pp))
            continue;
        const RigidPose& pose = s.poses[std::size_t(o.pose)];
        const Vec3 N{pose.R[2], pose.R[5], pose.R[8]};
        const double Nm = dot(N, m);
        // d r / d X = d pixel_p / d X_p R.
        double B[2][3];
        for (int r = 0; r < 2; ++r)
            for (int c = 0; c < 3; ++c)
                B[r][c] = pp.d_point[r][0] * s.R[std::size_t(c)] +
                          pp.d_point[r][1] * s.R[std::size_t(3 + c)] +
                          pp.d_point[r][2] * s.R[std::size_t(6 + c)];
        const auto add_moved = [&](int full, const Vec3& dX) {
            const int c = col1[std::size_t(full)];
            if (c >= 0)
                moved.push_back({c, B[0][0] * dX[0] + B[0][1] * dX[1] + B[0][2] * dX[2],
                                 B[1][0] * dX[0] + B[1][1] * dX[1] + B[1][2] * dX[2]});
        };
        // The ray: A dn = -rhs with A = d pixel_c / d (xn, yn).
        const double a = pc.d_point[0][0], b = pc.d_point[0][1], c = pc.d_point[1][0],
                     d = pc.d_point[1][1];
        const double det = a * d - b * c;
        if (!(std::fabs(det) > 0))
            continue;
        const auto ray_moved = [&](int full, double ru, double rv) {
            const double dx = -(d * ru - b * rv) / det, dy = -(-c * ru + a * rv) / det;
            const Vec3 dm{dx, dy, 0};
            const double dz = -z * dot(N, dm) / Nm;
            add_moved(full, {dz * m[0] + z * dm[0], dz * m[1] + z * dm[1], dz * m[2]});
        };
        moved.clear();
        for (int k = 0; k < kLensParameters; ++k)
            ray_moved(order.camera_lens + k, pc.d_lens[0][k], pc.d_lens[1][k]);
        if (!s.camera_grid.empty())
            for (int k = 0; k < CorrectionGrid::kSupport; ++k) {
                const int at = order.camera_grid + 2 * pc.grid_index[k];
                ray_moved(at, pc.grid_weight[k], 0);
                ray_moved(at + 1, 0, pc.grid_weight[k]);
            }
        // The plane: R <- exp([w]x) R turns N by w x N; t moves d by N . dt.
        const int base = order.poses + 6 * o.pose;
        for (int j = 0; j < 3; ++j) {
            Vec3 e{0, 0, 0};
            e[std::size_t(j)] = 1;
            const Vec3 dN = cross(e, N);
            const double dz_w = (dot(dN, pose.t) - z * dot(dN, m)) / Nm;
            add_moved(base + j, {dz_w * m[0], dz_w * m[1], dz_w * m[2]});
            const double dz_t = N[std::size_t(j)] / Nm;
            add_moved(base + 3 + j, {dz_t * m[0], dz_t * m[1], dz_t * m[2]});
        }

        // The projector stage's own derivatives of the same residuals.
        projector.clear();
        const auto add_projector = [&](int full, double du, double dv) {
            const int r = col2[std::size_t(full)];
            if (r >= 0)
                projector.push_back({r, du, dv});
        };
        for (int k = 0; k < kLensParameters; ++k)
            add_projector(order.projector_lens + k, pp.d_lens[0][k], pp.d_lens[1][k]);
        if (!s.projector_grid.empty())
            for (int k = 0; k < CorrectionGrid::kSupport; ++k) {
                const int at = order.projector_grid + 2 * pp.grid_index[k];
                add_projector(at, pp.grid_weight[k], 0);
                add_projector(at + 1, 0, pp.grid_weight[k]);
            }
        for (int j = 0; j < 3; ++j) {
            Vec3 e{0, 0, 0};
            e[std::size_t(j)] = 1;
            const Vec3 dXp = cross(e, rotated);
            add_projector(order.stereo + j,
                          dot({pp.d_point[0][0], pp.d_point[0][1], pp.d_point[0][2]}, dXp),
                          dot({pp.d_point[1][0], pp.d_point[1][1], pp.d_point[1][2]}, dXp));
            add_projector(order.stereo + 3 + j, pp.d_point[0][j], pp.d_point[1][j]);
        }
        const double w = o.weight * projector_stage.dense_weight;
        for (const Entry& p : projector)
            for (const Entry& q : moved)
                M(p.column, q.column) += w * (p.du * q.du + p.dv * q.dv);
    }
    return M;
}

Eigen::MatrixXd projector_response_by_differences(
    const RigState& s, const std::vector<CornerObservation>& corners,
    const std::vector<DenseObservation>& dense, const std::vector<bool>& pose_used,
    const FreeParameters& camera_stage, const FreeParameters& projector_stage,
    const GridRegularisation& regularisation, const std::vector<double>& steps) {
    const Eigen::Index n1 = Eigen::Index(steps.size());
    Eigen::MatrixXd M;
    std::vector<double> step(steps.size(), 0.0);
    std::vector<DenseObservation> moved;
    const auto gradient_at = [&](Eigen::Index k, double h) {
        RigState t = s;
        step.assign(steps.size(), 0.0);
        step[std::size_t(k)] = h;
        apply_increment(t, pose_used, camera_stage, step);
        moved = dense;
        place_dense_points(t, moved);
        return normal_equations(t, corners, moved, pose_used, projector_stage, regularisation).g;
    };
    for (Eigen::Index k = 0; k < n1; ++k) {
        const double h = steps[std::size_t(k)];
        const Eigen::VectorXd g = (gradient_at(k, h) - gradient_at(k, -h)) / (2 * h);
        if (M.size() == 0)
            M = Eigen::MatrixXd::Zero(g.size(), n1);
        M.col(k) = g;
    }
    return M;
}

} // namespace fpp::calib::detail
