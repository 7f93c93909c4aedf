// The stereo bundle adjustment's analytic Jacobians against central
// differences of its cost, for every kind of parameter and observation: lens
// parameters, correction grids, the stereo transform, board poses, corners
// of both devices and dense samples, each kind with its own weight.

#include "stereo/bundle_adjustment.hpp"
#include "trueness/calibration_covariance.hpp"

#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/session.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using namespace fpp;
using namespace fpp::calib;
using namespace fpp::calib::detail;

struct Problem {
    RigState state;
    std::vector<CornerObservation> corners;
    std::vector<DenseObservation> dense;
    std::vector<bool> used;
};

Vec3 to_camera(const RigidPose& p, const Vec3& b) {
    const Vec3 r = mul(p.R, b);
    return {r[0] + p.t[0], r[1] + p.t[1], r[2] + p.t[2]};
}

// Three board poses of the lens-defects rig (camera binned 4x), grids of
// random displacements, observations of a perturbed copy of the state so
// that every residual is non-zero.
Problem make_problem() {
    const sim::Rig rig = sim::load_rig(sim::lens_defects_rig_path()).binned_camera(4);
    sim::SessionOptions session;
    session.poses = 3;
    const std::vector<sim::Pose> poses = sim::session_poses(rig, session);
    Problem p;
    RigState& s = p.state;
    s.camera = rig.camera;
    s.projector = rig.projector;
    s.camera.drop_unmodelled_terms();
    s.projector.drop_unmodelled_terms();
    s.R = rig.R;
    s.T = rig.t;
    s.camera_grid = CorrectionGrid(rig.camera_size, 6, 5);
    s.projector_grid = CorrectionGrid(rig.projector_size, 6, 5);
    std::mt19937 random(7);
    std::normal_distribution<double> noise(0, 0.3);
    for (Vec2& v : s.camera_grid.values())
        v = {noise(random), noise(random)};
    for (Vec2& v : s.projector_grid.values())
        v = {noise(random), noise(random)};
    StereoCalibration model;
    model.camera = s.camera;
    model.camera_correction = s.camera_grid;
    model.projector = s.projector;
    model.projector_correction = s.projector_grid;
    model.R = s.R;
    model.T = s.T;
    for (std::size_t i = 0; i < poses.size(); ++i) {
        RigidPose pose{poses[i].R, poses[i].centre};
        s.poses.push_back(pose);
        p.used.push_back(true);
        for (int k = 0; k < 12; ++k) {
            const Vec3 board{(k % 4 - 1.5) * 40, (k / 4 - 1) * 40.0, 0};
            const Vec3 x = to_camera(pose, board);
            const Vec2 c = model.camera_pixel(x), q = model.projector_pixel(x);
            p.corners.push_back({int(i),
                                 board,
                                 {c[0] + noise(random), c[1] + noise(random)},
                                 {q[0] + noise(random), q[1] + noise(random)}});
            p.dense.push_back({x, {q[0] + noise(random), q[1] + noise(random)}, 0.5, int(i), c});
        }
    }
    return p;
}

// Every free parameter: (cost(+h) - cost(-h)) / 2h against 2 g.
void check_gradient(const FreeParameters& free) {
    const Problem p = make_problem();
    const GridRegularisation regularisation{0.5, 0.7, 0.01};
    const Linearisation at = linearise(p.state, p.corners, p.dense, p.used, free, regularisation);
    ASSERT_FALSE(at.gradient.empty());
    int checked = 0;
    for (std::size_t c = 0; c < at.gradient.size(); ++c) {
        // Steps in each parameter's own units (pixels, radians, mm).
        for (const double h : {1e-6, 1e-5, 1e-4}) {
            std::vector<double> step(at.gradient.size(), 0.0);
            step[c] = h;
            RigState plus = p.state, minus = p.state;
            apply_increment(plus, p.used, free, step);
            step[c] = -h;
            apply_increment(minus, p.used, free, step);
            const double cp =
                linearise(plus, p.corners, p.dense, p.used, free, regularisation, &p.state).cost;
            const double cm =
                linearise(minus, p.corners, p.dense, p.used, free, regularisation, &p.state).cost;
            const double numeric = (cp - cm) / (2 * h);
            const double analytic = 2 * at.gradient[c];
            const double scale = std::max({std::fabs(numeric), std::fabs(analytic), 1e-2});
            if (std::fabs(numeric - analytic) <= 1e-3 * scale) {
                ++checked;
                break;
            }
            if (h == 1e-4)
                ADD_FAILURE() << "parameter " << c << ": analytic " << analytic << ", numeric "
                              << numeric;
        }
    }
    EXPECT_EQ(checked, int(at.gradient.size()));
}

TEST(BundleAdjustment, CameraAloneGradientMatchesCentralDifferences) {
    FreeParameters free;
    free.camera_lens = free.camera_grid = free.poses = free.camera_observations = true;
    check_gradient(free);
}

TEST(BundleAdjustment, ProjectorWithTheBoardsHeldGradientMatchesCentralDifferences) {
    FreeParameters free;
    free.projector_lens = free.projector_grid = free.stereo = true;
    free.projector_observations = true;
    free.projector_weight = 2;
    free.dense_weight = 0.3;
    check_gradient(free);
}

TEST(BundleAdjustment, EverythingTogetherMatchesCentralDifferences) {
    FreeParameters free;
    free.camera_lens = free.camera_grid = free.projector_lens = free.projector_grid = true;
    free.stereo = free.poses = true;
    free.camera_observations = free.projector_observations = true;
    free.camera_weight = 3;
    free.projector_weight = 2;
    free.dense_weight = 0.3;
    check_gradient(free);
}

} // namespace

namespace {

// The covariance's cross term (trueness/calibration_covariance.hpp): how
// the projector stage's gradient moves with the camera stage's parameters,
// analytic against central differences of that gradient, every column. The
// projector's observations exact, so that the second-order terms the
// analytic form leaves out (residual times curvature) are zero.
TEST(CalibrationCovariance, ProjectorResponseMatchesCentralDifferences) {
    Problem p = make_problem();
    StereoCalibration model;
    model.projector = p.state.projector;
    model.projector_correction = p.state.projector_grid;
    model.R = p.state.R;
    model.T = p.state.T;
    for (DenseObservation& o : p.dense)
        o.projector = model.projector_pixel(o.camera_point);
    for (CornerObservation& o : p.corners)
        o.projector = model.projector_pixel(to_camera(p.state.poses[std::size_t(o.pose)], o.board));
    FreeParameters camera;
    camera.camera_lens = camera.camera_grid = camera.poses = camera.camera_observations = true;
    camera.camera_weight = 4;
    FreeParameters projector;
    projector.projector_lens = projector.projector_grid = projector.stereo = true;
    projector.projector_observations = true;
    projector.projector_weight = 3;
    projector.dense_weight = 2;
    const GridRegularisation regularisation;
    const NormalEquations one =
        normal_equations(p.state, p.corners, {}, p.used, camera, regularisation);
    const NormalEquations two =
        normal_equations(p.state, p.corners, p.dense, p.used, projector, regularisation);
    const FullOrder order = full_order(p.state);
    std::vector<double> steps;
    for (int full : one.full_index) {
        const int lens = full - order.camera_lens;
        if (full >= order.poses)
            steps.push_back((full - order.poses) % 6 < 3 ? 1e-6 : 1e-4);
        else if (lens >= 0 && lens < kLensParameters)
            steps.push_back(lens < 5 ? 1e-4 : 1e-6);
        else
            steps.push_back(1e-4); // grid, px
    }
    const Eigen::MatrixXd analytic = projector_response(p.state, p.corners, p.dense, p.used,
                                                        one.full_index, two.full_index, projector);
    const Eigen::MatrixXd numeric = projector_response_by_differences(
        p.state, p.corners, p.dense, p.used, camera, projector, regularisation, steps);
    ASSERT_EQ(analytic.rows(), numeric.rows());
    ASSERT_EQ(analytic.cols(), numeric.cols());
    int checked = 0;
    for (Eigen::Index c = 0; c < numeric.cols(); ++c) {
        const double scale = std::max(numeric.col(c).cwiseAbs().maxCoeff(), 1e-9);
        const double error = (analytic.col(c) - numeric.col(c)).cwiseAbs().maxCoeff();
        EXPECT_LT(error, 1e-4 * scale) << "camera-stage column " << c << " (full index "
                                       << one.full_index[std::size_t(c)] << ")";
        checked += numeric.col(c).cwiseAbs().maxCoeff() > 0;
    }
    EXPECT_GT(checked, numeric.cols() / 2);
}

} // namespace
