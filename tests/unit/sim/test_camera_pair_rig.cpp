// Two cameras and one projector (fpp/simulator/camera_pair_rig.hpp): the
// binocular rig's geometry (the second camera's centre on the baseline, its
// axis on the convergence point, rows kept level, its own lens), the one
// projector seen from both cameras, binning, refusals, and a scene moved
// into the second camera's frame hit where the first camera's ray hits it.

#include "fpp/simulator/camera_pair_rig.hpp"

#include "fpp/lens_model.hpp"
#include "fpp/vec3.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

using namespace fpp;
using namespace fpp::sim;

namespace {

void expect_near(const Vec3& a, const Vec3& b, double tolerance, const std::string& what) {
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(a[std::size_t(i)], b[std::size_t(i)], tolerance) << what << " [" << i << "]";
}

std::string refusal(double baseline, double converge) {
    try {
        binocular_rig(Rig::paper(), baseline, converge);
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "accepted";
}

TEST(CameraPairRig, TheSecondCameraSitsOnTheBaselineLookingAtTheConvergencePoint) {
    const Rig first = Rig::paper();
    const CameraPairRig pair = binocular_rig(first, 250.0, 480.0);
    // Its centre in the first camera's frame: -R^T T.
    expect_near(vec::scale(mul(transpose(pair.R), pair.T), -1.0), Vec3{250, 0, 0}, 1e-12, "centre");
    // R is a rotation.
    const Mat3 RRt = mul(pair.R, transpose(pair.R));
    for (int i = 0; i < 9; ++i)
        EXPECT_NEAR(RRt[std::size_t(i)], i % 4 == 0 ? 1.0 : 0.0, 1e-12) << i;
    const Vec3 x = {pair.R[0], pair.R[1], pair.R[2]}, y = {pair.R[3], pair.R[4], pair.R[5]},
               z = {pair.R[6], pair.R[7], pair.R[8]};
    EXPECT_NEAR(vec::dot(vec::cross(x, y), z), 1.0, 1e-12); // right-handed
    // Its axis toward (0, 0, 480) from (250, 0, 0); its rows level.
    const double length = std::hypot(250.0, 480.0);
    expect_near(z, Vec3{-250.0 / length, 0, 480.0 / length}, 1e-12, "axis");
    EXPECT_EQ(x[1], 0.0);
    expect_near(y, Vec3{0, 1, 0}, 1e-12, "down");
    // The convergence point is on the second camera's axis.
    const Vec3 target = vec::add(mul(pair.R, Vec3{0, 0, 480}), pair.T);
    EXPECT_NEAR(target[0], 0.0, 1e-9);
    EXPECT_NEAR(target[1], 0.0, 1e-9);
    EXPECT_NEAR(target[2], length, 1e-9);
}

TEST(CameraPairRig, TheSecondCameraHasItsOwnLensAndTheFirstsSensorAndProjector) {
    const Rig first = Rig::paper();
    const CameraPairRig pair = binocular_rig(first);
    EXPECT_EQ(pair.first.name, first.name);
    EXPECT_EQ(pair.second.name, first.name + "-second-camera");
    EXPECT_DOUBLE_EQ(pair.second.camera.fu, first.camera.fu * 1.004);
    EXPECT_DOUBLE_EQ(pair.second.camera.fv, first.camera.fv * 1.004);
    EXPECT_DOUBLE_EQ(pair.second.camera.cu, first.camera.cu + 9.0);
    EXPECT_DOUBLE_EQ(pair.second.camera.cv, first.camera.cv - 6.0);
    EXPECT_DOUBLE_EQ(pair.second.camera.k1, first.camera.k1 - 0.01);
    EXPECT_EQ(pair.second.camera_size, first.camera_size);
    EXPECT_EQ(pair.second.projector_size, first.projector_size);
    EXPECT_EQ(pair.second.sensor.white_level, first.sensor.white_level);
}

TEST(CameraPairRig, BothCamerasSeeTheOneProjector) {
    const CameraPairRig pair = binocular_rig(Rig::paper(), 180.0, 520.0);
    // A point in the first camera's frame reaches the projector's frame the
    // same way through either camera: X_p = R_1 X_1 + t_1 = R_2 X_2 + t_2.
    for (const Vec3& X1 : {Vec3{0, 0, 500}, Vec3{-120, 80, 430}, Vec3{60, -40, 610}}) {
        const Vec3 via_first = vec::add(mul(pair.first.R, X1), pair.first.t);
        const Vec3 X2 = vec::add(mul(pair.R, X1), pair.T);
        const Vec3 via_second = vec::add(mul(pair.second.R, X2), pair.second.t);
        expect_near(via_second, via_first, 1e-9, "projector frame");
    }
    // The projector's centre, seen from each camera, is one point.
    const Vec3 from_second = pair.second.projector_centre_in_camera();
    const Vec3 from_first = pair.first.projector_centre_in_camera();
    expect_near(from_second, vec::add(mul(pair.R, from_first), pair.T), 1e-9, "projector centre");
}

TEST(CameraPairRig, SecondCameraRigOfTheSamePoseIsTheFirst) {
    const Rig first = Rig::paper();
    const Rig same = second_camera_rig(first, first.camera, first.camera_size,
                                       {1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 0});
    EXPECT_EQ(same.R, first.R);
    EXPECT_EQ(same.t, first.t);
    EXPECT_EQ(same.name, first.name + "-second-camera");
}

TEST(CameraPairRig, BinningBothCamerasKeepsThePose) {
    const CameraPairRig pair = binocular_rig(Rig::paper());
    const CameraPairRig half = binned(pair, 2);
    EXPECT_EQ(half.first.camera_size.width, pair.first.camera_size.width / 2);
    EXPECT_EQ(half.second.camera_size.height, pair.second.camera_size.height / 2);
    EXPECT_DOUBLE_EQ(half.second.camera.fu, pair.second.camera.fu / 2);
    EXPECT_EQ(half.R, pair.R);
    EXPECT_EQ(half.T, pair.T);
    EXPECT_EQ(half.second.R, pair.second.R);
}

TEST(CameraPairRig, RefusesABaselineOrDistanceThatIsNotPositive) {
    const std::string message = "binocular_rig: baseline and convergence distance must be > 0";
    EXPECT_EQ(refusal(0, 480), message);
    EXPECT_EQ(refusal(-250, 480), message);
    EXPECT_EQ(refusal(250, 0), message);
    EXPECT_EQ(refusal(250, std::nan("")), message);
    EXPECT_EQ(refusal(250, 480), "accepted");
}

TEST(CameraPairRig, AMovedSceneIsHitWhereTheFirstCamerasRayHitsIt) {
    auto scene = std::make_shared<Scene>();
    scene->add(std::make_unique<Sphere>(Vec3{10, -5, 500}, 40.0, 0.8), "ball", {0.1, 50});
    const CameraPairRig pair = binocular_rig(Rig::paper());
    const Scene moved = scene_seen_from(scene, pair.R, pair.T);
    ASSERT_EQ(moved.size(), 1u);
    EXPECT_EQ(moved.object_name(0), "ball");
    EXPECT_EQ(moved.specular(0).specular, 0.1);
    EXPECT_EQ(moved.specular(0).shininess, 50.0);
    // The first camera's ray to the ball's front, and the second camera's ray
    // to the same point: the same point, the normal turned with it.
    Hit hit1;
    ASSERT_TRUE(scene->intersect({0, 0, 0}, vec::normalised(Vec3{10, -5, 500}), hit1));
    const Vec3 in_second = vec::add(mul(pair.R, hit1.point), pair.T);
    Hit hit2;
    ASSERT_TRUE(moved.intersect({0, 0, 0}, vec::normalised(in_second), hit2));
    expect_near(hit2.point, in_second, 1e-6, "hit point");
    EXPECT_NEAR(hit2.t, vec::norm(in_second), 1e-6);
    const Vec3 centre2 = vec::add(mul(pair.R, Vec3{10, -5, 500}), pair.T);
    expect_near(hit2.normal, vec::normalised(vec::sub(hit2.point, centre2)), 1e-9, "normal");
    EXPECT_EQ(hit2.albedo, 0.8);
    // A ray that misses the ball misses it moved too.
    EXPECT_FALSE(moved.intersect({0, 0, 0}, {0, 0, -1}, hit2));
    EXPECT_THROW(scene_seen_from(nullptr, pair.R, pair.T), std::invalid_argument);
}

} // namespace
