// The covariance of a stereo calibration (see calibration_covariance.hpp).

#include "calibration_covariance.hpp"

#include "fpp/calib/stereo_calibration.hpp"

#include <cmath>

namespace fpp::calib::detail {

namespace {

// Weighted squared residuals per degree of freedom (1 when there is none
// to spare: the weights are then taken as the noise).
double variance_factor(const NormalEquations& n) {
    const int dof = n.residuals - static_cast<int>(n.g.size());
    return dof > 0 ? n.data_cost / dof : 1.0;
}

// Inverse of a symmetric positive definite matrix, scaled to unit diagonal
// first: its parameters span focal lengths of thousands of pixels and
// distortion terms of 1e-4.
Eigen::MatrixXd inverse(const Eigen::MatrixXd& A) {
    Eigen::VectorXd d = A.diagonal().cwiseSqrt();
    for (Eigen::Index k = 0; k < d.size(); ++k)
        if (!(d(k) > 0))
            d(k) = 1;
    const Eigen::MatrixXd scaled = d.asDiagonal().inverse() * A * d.asDiagonal().inverse();
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(scaled);
    const Eigen::MatrixXd inv = ldlt.solve(Eigen::MatrixXd::Identity(scaled.rows(), scaled.cols()));
    return d.asDiagonal().inverse() * inv * d.asDiagonal().inverse();
}

// Copies the block of a stage's covariance between columns `rows_of` and
// `cols_of` (full indices) into the calibration's matrix, leaving out the
// poses.
void scatter(Eigen::MatrixXd& out, const Eigen::MatrixXd& block, const std::vector<int>& rows_of,
             const std::vector<int>& cols_of) {
    for (std::size_t a = 0; a < rows_of.size(); ++a)
        for (std::size_t b = 0; b < cols_of.size(); ++b)
            if (rows_of[a] < out.rows() && cols_of[b] < out.cols()) {
                out(rows_of[a], cols_of[b]) = block(Eigen::Index(a), Eigen::Index(b));
                out(cols_of[b], rows_of[a]) = block(Eigen::Index(a), Eigen::Index(b));
            }
}

} // namespace

void place_dense_points(const RigState& s, std::vector<DenseObservation>& dense,
                        std::vector<bool>* placed) {
    const StereoCalibration camera_model = calibration_of(s);
    if (placed)
        placed->assign(dense.size(), false);
    for (std::size_t k = 0; k < dense.size(); ++k) {
        DenseObservation& o = dense[k];
        const RigidPose& pose = s.poses[std::size_t(o.pose)];
        // The board plane n . X = d in the camera frame: n the board's z axis.
        const Vec3 normal{pose.R[2], pose.R[5], pose.R[8]};
        const double d = normal[0] * pose.t[0] + normal[1] * pose.t[1] + normal[2] * pose.t[2];
        Vec2 n{};
        if (!camera_model.camera_ray(o.camera, n))
            continue;
        const double den = normal[0] * n[0] + normal[1] * n[1] + normal[2];
        const double z = d / den;
        if (!(std::fabs(den) > 1e-9) || !(z > 0))
            continue;
        o.camera_point = {n[0] * z, n[1] * z, z};
        if (placed)
            (*placed)[k] = true;
    }
}

FreeParameters calibration_parameters() {
    FreeParameters free;
    free.camera_lens = free.projector_lens = free.stereo = true;
    free.camera_grid = free.projector_grid = true;
    free.skew = true;
    return free;
}

CalibrationCovariance joint_covariance(const RigState& s,
                                       const std::vector<CornerObservation>& corners,
                                       const std::vector<bool>& pose_used,
                                       const FreeParameters& free,
                                       const GridRegularisation& regularisation, ThreadPool* pool) {
    const int size = full_order(s).poses;
    const NormalEquations n =
        normal_equations(s, corners, {}, pose_used, free, regularisation, pool);
    CalibrationCovariance out;
    out.pose_stage = free;
    out.pose_stage_variance = variance_factor(n);
    out.pose_stage_index = n.full_index;
    out.transfer = Eigen::MatrixXd::Zero(size, Eigen::Index(n.full_index.size()));
    for (std::size_t c = 0; c < n.full_index.size(); ++c)
        if (n.full_index[c] < size)
            out.transfer(n.full_index[c], Eigen::Index(c)) = 1;
    out.own = Eigen::MatrixXd::Zero(size, size);
    out.sigma = out.transfer * (out.pose_stage_variance * inverse(n.A)) * out.transfer.transpose();
    out.pose_stage_normal = n.A;
    return out;
}

CalibrationCovariance
camera_first_covariance(const RigState& s, const std::vector<CornerObservation>& corners,
                        const std::vector<DenseObservation>& dense,
                        const std::vector<bool>& pose_used, const FreeParameters& camera_stage,
                        const FreeParameters& projector_stage,
                        const GridRegularisation& regularisation, ThreadPool* pool) {
    const int size = full_order(s).poses;
    const NormalEquations one =
        normal_equations(s, corners, {}, pose_used, camera_stage, regularisation, pool);
    const double s1 = variance_factor(one);
    const Eigen::MatrixXd sigma_1 = s1 * inverse(one.A);
    const NormalEquations two =
        normal_equations(s, corners, dense, pose_used, projector_stage, regularisation, pool);
    const Eigen::MatrixXd two_inverse = inverse(two.A);

    const Eigen::Index n1 = sigma_1.rows(), n2 = two_inverse.rows();
    const Eigen::MatrixXd M = projector_response(s, corners, dense, pose_used, one.full_index,
                                                 two.full_index, projector_stage);
    // d theta_2 = -B d theta_1.
    const Eigen::MatrixXd B = two_inverse * M;

    CalibrationCovariance out;
    out.pose_stage = camera_stage;
    out.pose_stage_normal = one.A;
    out.pose_stage_variance = s1;
    out.pose_stage_index = one.full_index;
    out.transfer = Eigen::MatrixXd::Zero(size, n1);
    for (Eigen::Index c = 0; c < n1; ++c)
        if (one.full_index[std::size_t(c)] < size)
            out.transfer(one.full_index[std::size_t(c)], c) = 1;
    for (Eigen::Index r = 0; r < n2; ++r)
        if (two.full_index[std::size_t(r)] < size)
            out.transfer.row(two.full_index[std::size_t(r)]) = -B.row(r);
    out.own = Eigen::MatrixXd::Zero(size, size);
    scatter(out.own, variance_factor(two) * two_inverse, two.full_index, two.full_index);
    out.sigma = out.transfer * sigma_1 * out.transfer.transpose() + out.own;
    return out;
}

} // namespace fpp::calib::detail
