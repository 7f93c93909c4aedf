// Scenes: ray-shape intersections against analytic values, the relief's
// robust marching, composites with occlusion and projector shadows, named
// scenes and scene YAML files.

#include "fpp/error.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

namespace {

using fpp::Vec3;
using namespace fpp::sim;

const fpp::Mat3 kIdentity{1, 0, 0, 0, 1, 0, 0, 0, 1};

Vec3 unit(Vec3 v) {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return {v[0] / n, v[1] / n, v[2] / n};
}
using fpp::vec::dot;
double distance(const Vec3& a, const Vec3& b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                     (a[2] - b[2]) * (a[2] - b[2]));
}
Vec3 at(const Vec3& o, const Vec3& d, double t) {
    return {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
}
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(SimScene, PlaneHitAndBounds) {
    const Pose pose = Pose::from_euler_deg({10, -5, 480}, 0, 30, 0); // normal tilted 30 deg about y
    const Plane plane(pose, 200, 100, 0.7);
    const Vec3 o{0, 0, 0};
    const Vec3 d = unit({0.05, -0.02, 1});
    fpp::sim::Hit hit;
    ASSERT_TRUE(plane.intersect(o, d, 0, kInf, hit));
    // Analytic: t = (c - o).n / (d.n).
    const Vec3 n{std::sin(30 * M_PI / 180), 0, std::cos(30 * M_PI / 180)};
    EXPECT_NEAR(hit.t, dot({10, -5, 480}, n) / dot(d, n), 1e-9);
    EXPECT_NEAR(dot({hit.point[0] - 10, hit.point[1] + 5, hit.point[2] - 480}, n), 0, 1e-9);
    EXPECT_LT(dot(hit.normal, d), 0); // faces the ray origin
    EXPECT_EQ(hit.albedo, 0.7);
    // Outside the 200 x 100 rectangle, and behind tmax.
    EXPECT_FALSE(plane.intersect(o, unit({0.0, 0.2, 1}), 0, kInf, hit));
    EXPECT_FALSE(plane.intersect(o, d, 0, 400, hit));
}

TEST(SimScene, SphereAnalytic) {
    const Sphere s({20, -10, 500}, 40, 0.9);
    fpp::sim::Hit hit;
    // Through the centre: t = |c| - r.
    const Vec3 c{20, -10, 500};
    const double dc = std::sqrt(dot(c, c));
    ASSERT_TRUE(s.intersect({0, 0, 0}, unit(c), 0, kInf, hit));
    EXPECT_NEAR(hit.t, dc - 40, 1e-9);
    EXPECT_NEAR(dot(hit.normal, unit(c)), -1, 1e-12);
    // Off-centre ray at perpendicular distance b from the centre: t = d.c - sqrt(r^2 - b^2).
    const Vec3 d = unit({0.06, -0.02, 1});
    const double along = dot(d, c);
    const double b2 = dot(c, c) - along * along;
    ASSERT_TRUE(s.intersect({0, 0, 0}, d, 0, kInf, hit));
    EXPECT_NEAR(hit.t, along - std::sqrt(1600 - b2), 1e-9);
    EXPECT_NEAR(distance(hit.point, c), 40, 1e-9);
    // From inside the sphere the far side is hit.
    ASSERT_TRUE(s.intersect(c, {0, 0, 1}, 1e-9, kInf, hit));
    EXPECT_NEAR(hit.t, 40, 1e-12);
    EXPECT_NEAR(hit.normal[2], -1, 1e-12); // facing the origin, inside
    // A ray that passes 40.001 mm from the centre misses.
    EXPECT_FALSE(s.intersect({60.001, -10, 0}, {0, 0, 1}, 0, kInf, hit));
    ASSERT_TRUE(s.intersect({59.999, -10, 0}, {0, 0, 1}, 0, kInf, hit));
}

TEST(SimScene, CylinderAnalytic) {
    // Axis along y through (0, 0, 500), radius 60, length 240, closed.
    const Cylinder cyl({0, 0, 500}, {0, 1, 0}, 60, 240, 0.8);
    fpp::sim::Hit hit;
    ASSERT_TRUE(cyl.intersect({0, 0, 0}, {0, 0, 1}, 0, kInf, hit));
    EXPECT_NEAR(hit.t, 440, 1e-9);
    EXPECT_NEAR(hit.normal[2], -1, 1e-12);
    // A ray at x = 30: z = 500 - sqrt(60^2 - 30^2).
    ASSERT_TRUE(cyl.intersect({30, 50, 0}, {0, 0, 1}, 0, kInf, hit));
    EXPECT_NEAR(hit.point[2], 500 - std::sqrt(3600.0 - 900.0), 1e-9);
    EXPECT_NEAR(hit.normal[0], 0.5, 1e-12);
    // Beyond the length: misses the side; along the axis: hits the cap at y = -120.
    EXPECT_FALSE(cyl.intersect({0, 125, 0}, {0, 0, 1}, 0, kInf, hit));
    ASSERT_TRUE(cyl.intersect({10, -300, 500}, {0, 1, 0}, 0, kInf, hit));
    EXPECT_NEAR(hit.t, 180, 1e-9);
    EXPECT_NEAR(hit.normal[1], -1, 1e-12);
    // An oblique ray, checked against the implicit surface.
    const Vec3 o{-100, 20, 0};
    const Vec3 d = unit({0.2, 0.05, 1});
    ASSERT_TRUE(cyl.intersect(o, d, 0, kInf, hit));
    EXPECT_NEAR(std::hypot(hit.point[0], hit.point[2] - 500), 60, 1e-9);
}

TEST(SimScene, ReliefSingleBumpAnalytic) {
    // One bump of 20 mm over a 100 x 100 mm patch at 500 mm, rising toward the camera.
    const Relief relief(Pose{{0, 0, 500}, kIdentity}, 100, 100, {{5, -3, 20, 30, 25}}, 0.8);
    EXPECT_NEAR(relief.height_at(5, -3), 20, 1e-12);
    EXPECT_NEAR(relief.height_at(5 + 15, -3), 20 * std::pow(1 - 0.25, 3), 1e-12);
    EXPECT_EQ(relief.height_at(40, -3), 0); // outside the bump's support
    fpp::sim::Hit hit;
    // Straight down the bump's axis: t = 500 - 20.
    ASSERT_TRUE(relief.intersect({5, -3, 0}, {0, 0, 1}, 0, kInf, hit));
    EXPECT_NEAR(hit.t, 480, 1e-9);
    EXPECT_NEAR(hit.normal[2], -1, 1e-12);
    // Beside the bump the patch is flat at 500 mm.
    ASSERT_TRUE(relief.intersect({45, 45, 0}, {0, 0, 1}, 0, kInf, hit));
    EXPECT_NEAR(hit.t, 500, 1e-9);
    // Outside the rectangle: nothing.
    EXPECT_FALSE(relief.intersect({51, 0, 0}, {0, 0, 1}, 0, kInf, hit));
}

TEST(SimScene, ReliefCameraRaysHitTheSurfaceTo1e9mm) {
    const Relief relief(Pose::from_euler_deg({-20, 10, 505}, 5, -8, 3), 160, 220,
                        Relief::face_bumps(), 0.8);
    int exact = 0, total = 0;
    for (double y = -105; y <= 105; y += 7.3)
        for (double x = -75; x <= 75; x += 6.1) {
            const Vec3 p = relief.surface_point(x, y);
            const double dist = std::sqrt(dot(p, p));
            const Vec3 d{p[0] / dist, p[1] / dist, p[2] / dist};
            fpp::sim::Hit hit;
            ++total;
            ASSERT_TRUE(relief.intersect({0, 0, 0}, d, 0, kInf, hit)) << x << " " << y;
            // The first crossing is at or before the surface point (nearer
            // parts of the face, e.g. the nose, can hide it).
            EXPECT_LE(hit.t, dist + 1e-9);
            if (std::fabs(hit.t - dist) < 1e-9)
                ++exact;
            // The hit lies on the surface: its local height equals h(x, y).
            const fpp::Mat3 Rt = fpp::transpose(Pose::from_euler_deg({0, 0, 0}, 5, -8, 3).R);
            const Vec3 local =
                fpp::mul(Rt, Vec3{hit.point[0] + 20, hit.point[1] - 10, hit.point[2] - 505});
            EXPECT_NEAR(-local[2], relief.height_at(local[0], local[1]), 1e-9);
            // The normal is the surface's (checked against finite differences).
            const double e = 1e-5;
            const Vec3 px = relief.surface_point(local[0] + e, local[1]);
            const Vec3 mx = relief.surface_point(local[0] - e, local[1]);
            const Vec3 py = relief.surface_point(local[0], local[1] + e);
            const Vec3 my = relief.surface_point(local[0], local[1] - e);
            const Vec3 tx{px[0] - mx[0], px[1] - mx[1], px[2] - mx[2]};
            const Vec3 ty{py[0] - my[0], py[1] - my[1], py[2] - my[2]};
            EXPECT_NEAR(dot(hit.normal, unit(tx)), 0, 1e-6);
            EXPECT_NEAR(dot(hit.normal, unit(ty)), 0, 1e-6);
        }
    EXPECT_GT(exact, total * 9 / 10);
}

// The first crossing of the ray with the relief, by brute force: sample the
// ray every 0.01 mm, then bisect.
bool brute_force_relief(const Relief& relief, const Pose& pose, const Vec3& o, const Vec3& d,
                        double& t_hit) {
    const fpp::Mat3 Rt = fpp::transpose(pose.R);
    auto f = [&](double t, bool& inside) {
        const Vec3 p = at(o, d, t);
        const Vec3 l =
            fpp::mul(Rt, Vec3{p[0] - pose.centre[0], p[1] - pose.centre[1], p[2] - pose.centre[2]});
        inside = std::fabs(l[0]) <= 50 && std::fabs(l[1]) <= 50;
        return -l[2] - relief.height_at(l[0], l[1]);
    };
    bool inside = false, inside_prev = false;
    double prev = f(0, inside_prev);
    for (double t = 0.01; t < 1000; t += 0.01) {
        const double cur = f(t, inside);
        if (inside && inside_prev && (cur > 0) != (prev > 0)) {
            double a = t - 0.01, b = t;
            bool dummy = false;
            const double fa_sign = prev;
            for (int i = 0; i < 80; ++i) {
                const double m = 0.5 * (a + b);
                if ((f(m, dummy) > 0) == (fa_sign > 0))
                    a = m;
                else
                    b = m;
            }
            t_hit = 0.5 * (a + b);
            return true;
        }
        prev = cur;
        inside_prev = inside;
    }
    return false;
}

TEST(SimScene, ReliefGrazingRaysFindTheFirstCrossing) {
    // A steep, narrow bump and a wide one; rays at 60-85 degrees from the
    // patch normal skim the surface, where naive marching skips thin crossings.
    const Pose pose{{0, 0, 500}, kIdentity};
    const Relief relief(pose, 100, 100,
                        {{0, 0, 15, 8, 30}, {20, 10, 8, 40, 40}, {-25, -20, -6, 15, 15}}, 0.8);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> uni(-1, 1);
    int checked = 0;
    for (int k = 0; k < 300; ++k) {
        const double elevation =
            (5 + 25 * (uni(rng) + 1) / 2) * M_PI / 180; // above the patch plane
        const double azimuth = uni(rng) * M_PI;
        const Vec3 d{std::cos(elevation) * std::cos(azimuth),
                     std::cos(elevation) * std::sin(azimuth),
                     std::sin(elevation)}; // +z: away from the camera side, into the patch
        // Start above the relief (toward the camera, -z) and aim at a random point of the patch.
        const Vec3 target{uni(rng) * 45, uni(rng) * 45, 500};
        const Vec3 o = at(target, d, -60 / std::sin(elevation));
        double t_ref = 0;
        fpp::sim::Hit hit;
        const bool ref = brute_force_relief(relief, pose, o, d, t_ref);
        const bool got = relief.intersect(o, d, 0, kInf, hit);
        ASSERT_EQ(got, ref) << k;
        if (ref) {
            EXPECT_NEAR(hit.t, t_ref, 1e-6) << k;
            ++checked;
        }
    }
    EXPECT_GT(checked, 200);
}

TEST(SimScene, CompositeOcclusionAndProjectorShadow) {
    const Scene scene = named_scene("composite");
    ASSERT_EQ(scene.size(), 3u);
    fpp::sim::Hit hit;
    // Occlusion: the ray toward the sphere's centre stops at the sphere, not the plane.
    const Vec3 sphere{80, 25, 450};
    const Vec3 d = unit(sphere);
    ASSERT_TRUE(scene.intersect({0, 0, 0}, d, hit));
    EXPECT_EQ(hit.object, 2);
    EXPECT_NEAR(hit.t, std::sqrt(dot(sphere, sphere)) - 38, 1e-9);
    // Beside the sphere the background plane at 540 mm is seen.
    ASSERT_TRUE(scene.intersect({0, 0, 0}, unit({0.28, -0.15, 1}), hit));
    EXPECT_EQ(hit.object, 0);
    EXPECT_NEAR(hit.point[2], 540, 1e-9);

    // Projector shadow: the plane point on the line from the projector centre
    // through the sphere's centre cannot see the projector.
    const Vec3 pc = Rig::paper().projector_centre_in_camera();
    const Vec3 to_sphere = unit({sphere[0] - pc[0], sphere[1] - pc[1], sphere[2] - pc[2]});
    const double s = (540 - pc[2]) / to_sphere[2];
    const Vec3 shadowed = at(pc, to_sphere, s);
    const Vec3 back = unit({pc[0] - shadowed[0], pc[1] - shadowed[1], pc[2] - shadowed[2]});
    EXPECT_TRUE(scene.occluded({shadowed[0], shadowed[1], shadowed[2] - 1e-6}, back,
                               distance(shadowed, pc)));
    // A plane point far from any object sees the projector.
    const Vec3 lit{130, -90, 540};
    const Vec3 back_lit = unit({pc[0] - lit[0], pc[1] - lit[1], pc[2] - lit[2]});
    EXPECT_FALSE(scene.occluded({lit[0], lit[1], lit[2] - 1e-6}, back_lit, distance(lit, pc)));
    // The relief shadows the plane to its left (the projector is to the right).
    const Vec3 left{-132, 0, 540};
    const Vec3 back_left = unit({pc[0] - left[0], pc[1] - left[1], pc[2] - left[2]});
    EXPECT_TRUE(scene.occluded({left[0], left[1], left[2] - 1e-6}, back_left, distance(left, pc)));
}

TEST(SimScene, CheckerboardPatternCornersAndAreaSampling) {
    CheckerboardSpec spec;
    spec.inner_columns = 5;
    spec.inner_rows = 4;
    spec.square_size = 10;
    spec.margin = 7;
    const Checkerboard board(Pose{{0, 0, 480}, kIdentity}, spec);
    // Corner (0, 0) at local (-20, -15); square (0, 0) (top-left) black.
    const auto corners = board.inner_corners();
    ASSERT_EQ(corners.size(), 20u);
    EXPECT_NEAR(corners[0][0], -20, 1e-12);
    EXPECT_NEAR(corners[0][1], -15, 1e-12);
    EXPECT_NEAR(corners[19][0], 20, 1e-12);
    EXPECT_NEAR(corners[19][1], 15, 1e-12);
    EXPECT_EQ(board.albedo_at(-25, -20), spec.black_albedo);
    EXPECT_EQ(board.albedo_at(-15, -20), spec.white_albedo);
    EXPECT_EQ(board.albedo_at(-15, -10), spec.black_albedo);
    EXPECT_EQ(board.albedo_at(-31, -20), spec.white_albedo); // margin
    fpp::sim::Hit hit;
    EXPECT_TRUE(
        board.intersect({0, 0, 0}, unit({36.9 / 480, 0, 1}), 0, kInf, hit)); // in the margin
    EXPECT_FALSE(board.intersect({0, 0, 0}, unit({37.1 / 480, 0, 1}), 0, kInf, hit));
    // A 1 x 1 mm footprint centred on a vertical edge at x = -20 averages the two albedos;
    // shifted left by 0.25 mm it is 3/4 of the white square on the left.
    ASSERT_TRUE(board.intersect({-20, -12, 0}, {0, 0, 1}, 0, kInf, hit));
    const double mean = 0.5 * (spec.black_albedo + spec.white_albedo);
    EXPECT_NEAR(board.footprint_albedo(hit, {1, 0, 0}, {0, 1, 0}), mean, 1e-12);
    ASSERT_TRUE(board.intersect({-20.25, -12, 0}, {0, 0, 1}, 0, kInf, hit));
    EXPECT_NEAR(board.footprint_albedo(hit, {1, 0, 0}, {0, 1, 0}),
                0.75 * spec.white_albedo + 0.25 * spec.black_albedo, 1e-12);
    // Away from edges the point sample is returned.
    ASSERT_TRUE(board.intersect({-25, -22, 0}, {0, 0, 1}, 0, kInf, hit));
    EXPECT_EQ(board.footprint_albedo(hit, {1, 0, 0}, {0, 1, 0}), spec.black_albedo);
}

TEST(SimScene, BallBarSpheresAreTheGivenDistanceApart) {
    Scene s;
    add_ball_bar(s, {0, 0, 480}, {1, 0, 0}, 150, 15, 0.85);
    ASSERT_EQ(s.size(), 2u);
    fpp::sim::Hit hit;
    ASSERT_TRUE(s.intersect({-75, 0, 0}, {0, 0, 1}, hit));
    EXPECT_NEAR(hit.t, 465, 1e-9);
    ASSERT_TRUE(s.intersect({75, 0, 0}, {0, 0, 1}, hit));
    EXPECT_NEAR(hit.t, 465, 1e-9);
    EXPECT_FALSE(s.intersect({0, 0, 0}, {0, 0, 1}, hit));
    EXPECT_THROW(add_ball_bar(s, {0, 0, 480}, {1, 0, 0}, 20, 15, 0.85), std::invalid_argument);
}

TEST(SimScene, NamedScenesLieInTheCalibrationVolume) {
    const Rig rig = Rig::paper().binned_camera(16);
    for (const auto& name : named_scene_names()) {
        const Scene scene = named_scene(name);
        int hits = 0;
        for (int v = 0; v < rig.camera_size.height; ++v)
            for (int u = 0; u < rig.camera_size.width; ++u) {
                fpp::Vec2 n{};
                ASSERT_TRUE(rig.camera.pixel_to_normalised({double(u), double(v)}, n));
                fpp::sim::Hit hit;
                if (!scene.intersect({0, 0, 0}, unit({n[0], n[1], 1}), hit))
                    continue;
                ++hits;
                EXPECT_GE(hit.point[2], 400) << name;
                EXPECT_LE(hit.point[2], 560) << name;
            }
        EXPECT_GT(hits, 100) << name;
    }
    EXPECT_THROW(named_scene("teapot"), std::invalid_argument);
}

// ---- YAML -------------------------------------------------------------------

fpp::sim::Scene scene_from_text(const fpp::test::TempDir& dir, const std::string& text) {
    const auto path = dir / "scene.yaml";
    std::ofstream(path) << text;
    return load_scene(path);
}

TEST(SimSceneYaml, CompositeFileIsTheBuiltInComposite) {
    const auto path = fpp::test::source_dir() / "board/sim/scenes/composite.yaml";
    const Scene file = load_scene(path);
    const Scene builtin = named_scene("composite");
    const Scene by_arg = scene_from_argument(path.string());
    ASSERT_EQ(file.size(), builtin.size());
    EXPECT_EQ(by_arg.size(), builtin.size());
    for (double y = -0.22; y <= 0.22; y += 0.011)
        for (double x = -0.29; x <= 0.29; x += 0.013) {
            fpp::sim::Hit a, b;
            const Vec3 d = unit({x, y, 1});
            ASSERT_EQ(file.intersect({0, 0, 0}, d, a), builtin.intersect({0, 0, 0}, d, b));
            EXPECT_EQ(a.object, b.object);
            EXPECT_EQ(a.t, b.t);
        }
}

TEST(SimSceneYaml, EveryShapeType) {
    fpp::test::TempDir dir;
    const Scene s = scene_from_text(dir, R"(format: fpp-scene/1
shapes:
  - {type: plane, centre: [0, 0, 540], euler_deg: [0, 10, 0], size: [400, 300], albedo: 0.8}
  - {type: checkerboard, centre: [0, 0, 500], inner_corners: [9, 6], square_size: 8,
     black_albedo: 0.05, white_albedo: 0.9}
  - {type: sphere, centre: [0, 0, 450], radius: 10, albedo: 0.9}
  - {type: cylinder, centre: [50, 0, 480], axis: [0, 2, 0], radius: 10, length: 50, albedo: 0.7}
  - {type: ball_bar, centre: [-60, 0, 470], axis: [0, 1, 0], distance: 60, radius: 10, albedo: 0.9}
  - {type: relief, centre: [100, 0, 520], size: [40, 40], albedo: 0.8, bumps: [[0, 0, 10, 15, 15]]}
)");
    ASSERT_EQ(s.size(), 7u);
    fpp::sim::Hit hit;
    ASSERT_TRUE(s.intersect({0, 0, 0}, {0, 0, 1}, hit));
    EXPECT_EQ(hit.object, 2);
    EXPECT_NEAR(hit.t, 440, 1e-9);
    ASSERT_TRUE(s.intersect({100, 0, 0}, {0, 0, 1}, hit));
    EXPECT_EQ(hit.object, 6);
    EXPECT_NEAR(hit.t, 510, 1e-9);
    ASSERT_TRUE(s.intersect({50, 0, 0}, {0, 0, 1}, hit));
    EXPECT_NEAR(hit.t, 470, 1e-9);
    ASSERT_TRUE(s.intersect({-60, 30, 0}, {0, 0, 1}, hit));
    EXPECT_NEAR(hit.t, 460, 1e-9);
}

void expect_scene_rejected(const std::string& shape_yaml, const std::string& field) {
    fpp::test::TempDir dir;
    const auto path = dir / "bad-scene.yaml";
    std::ofstream(path) << "format: fpp-scene/1\nshapes:\n" << shape_yaml;
    try {
        load_scene(path);
        ADD_FAILURE() << "accepted a scene with a bad " << field;
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_EQ(e.field(), field) << e.what();
        EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos);
    }
}

TEST(SimSceneYaml, Rejections) {
    expect_scene_rejected("  - {type: teapot, centre: [0, 0, 500]}\n", "shapes[0].type");
    expect_scene_rejected(
        "  - {type: sphere, centre: [0, 0, 500], radius: 5, albedo: 0.5, colour: red}\n",
        "shapes[0].colour");
    expect_scene_rejected("  - {type: sphere, centre: [0, 0, 500], radius: 5, albedo: 0.5}\n"
                          "  - {type: sphere, centre: [0, 0, 500], albedo: 0.5}\n",
                          "shapes[1].radius");
    expect_scene_rejected("  - {type: sphere, centre: [0, .nan, 500], radius: 5, albedo: 0.5}\n",
                          "shapes[0].centre[1]");
    expect_scene_rejected("  - {type: plane, centre: [0, 0, 500], size: [10, 10], albedo: 1.5}\n",
                          "shapes[0].albedo");
    expect_scene_rejected("  - {type: cylinder, centre: [0, 0, 500], axis: [0, 0, 0], radius: 5, "
                          "length: 5, albedo: 0.5}\n",
                          "shapes[0].axis");
    expect_scene_rejected("  - {type: relief, centre: [0, 0, 500], size: [10, 10], albedo: 0.5, "
                          "bumps: [[0, 0, 1, 0, 1]]}\n",
                          "shapes[0].bumps[0]");
    expect_scene_rejected("  - {type: checkerboard, centre: [0, 0, 500], inner_corners: [1, 5], "
                          "square_size: 8, black_albedo: 0, white_albedo: 1}\n",
                          "shapes[0].inner_corners");
    expect_scene_rejected(
        "  - {type: ball_bar, centre: [0, 0, 500], axis: [1, 0, 0], distance: 10, "
        "radius: 10, albedo: 0.5}\n",
        "shapes[0].distance");
    fpp::test::TempDir dir;
    const auto path = dir / "empty.yaml";
    std::ofstream(path) << "format: fpp-scene/1\nshapes: []\n";
    EXPECT_THROW(load_scene(path), fpp::InputError);
    EXPECT_THROW(scene_from_argument((dir / "none.yaml").string()), fpp::InputError);
}

TEST(SimSceneYaml, MaterialsAndNames) {
    fpp::test::TempDir dir;
    const Scene s = scene_from_text(dir, R"(format: fpp-scene/1
shapes:
  - {type: plane, name: background, centre: [0, 0, 540], size: [400, 300], albedo: 0.8}
  - {type: sphere, name: metal, centre: [0, 0, 450], radius: 10,
     material: {albedo: 0.2, specular: 0.5, shininess: 100}}
  - {type: cylinder, centre: [50, 0, 480], axis: [0, 1, 0], radius: 10, length: 50,
     material: {albedo: 0.3, specular: 0.25, roughness: 0.2}}
  - {type: checkerboard, name: board, centre: [0, 0, 500], inner_corners: [9, 6], square_size: 8,
     black_albedo: 0.05, white_albedo: 0.9, material: {specular: 0.1, shininess: 20}}
  - {type: ball_bar, name: bar, centre: [-60, 0, 470], axis: [0, 1, 0], distance: 60, radius: 10,
     material: {albedo: 0.7}}
  - {type: relief, name: dark, centre: [100, 0, 520], size: [40, 40],
     material: {albedo: 0.03, specular: 0}, bumps: [[0, 0, 10, 15, 15]]}
)");
    ASSERT_EQ(s.size(), 7u);
    const char* names[] = {"background", "metal", "object2", "board", "bar", "bar", "dark"};
    for (std::size_t i = 0; i < s.size(); ++i)
        EXPECT_EQ(s.object_name(i), names[i]) << i;
    EXPECT_FALSE(s.specular(0).active());
    EXPECT_EQ(s.specular(1).specular, 0.5);
    EXPECT_EQ(s.specular(1).shininess, 100);
    // roughness 0.2 -> 2 / 0.04 - 2 = 48.
    EXPECT_EQ(s.specular(2).specular, 0.25);
    EXPECT_NEAR(s.specular(2).shininess, 48, 1e-9);
    EXPECT_EQ(s.specular(3).shininess, 20);
    EXPECT_FALSE(s.specular(4).active());
    EXPECT_FALSE(s.specular(6).active());
    fpp::sim::Hit hit;
    ASSERT_TRUE(s.intersect({0, 0, 0}, {0, 0, 1}, hit));
    EXPECT_EQ(hit.object, 1);
    EXPECT_EQ(hit.albedo, 0.2);
    ASSERT_TRUE(s.intersect({-60, 30, 0}, {0, 0, 1}, hit));
    EXPECT_EQ(hit.albedo, 0.7);
    // The lobe's reflectance relative to white paper: ks (n + 8) / 8 cos^n.
    EXPECT_NEAR(s.specular(1).relative_reflectance(1.0), 0.5 * 108 / 8, 1e-12);
    EXPECT_NEAR(s.specular(1).relative_reflectance(std::cos(0.1)),
                0.5 * 108 / 8 * std::pow(std::cos(0.1), 100), 1e-12);
    EXPECT_EQ(s.specular(1).relative_reflectance(-0.5), 0.0);
    EXPECT_EQ(s.specular(0).relative_reflectance(1.0), 0.0);
}

TEST(SimSceneYaml, MaterialAndNameRejections) {
    const std::string sphere = "  - {type: sphere, centre: [0, 0, 500], radius: 5, ";
    expect_scene_rejected(sphere + "albedo: 0.5, material: {albedo: 0.5}}\n", "shapes[0].albedo");
    expect_scene_rejected(sphere + "name: plain}\n", "shapes[0].albedo");
    expect_scene_rejected(sphere + "material: {specular: 0.5, shininess: 10}}\n",
                          "shapes[0].material.albedo");
    expect_scene_rejected(sphere + "material: {albedo: 1.2}}\n", "shapes[0].material.albedo");
    expect_scene_rejected(sphere + "material: {albedo: 0.2, specular: 1.5, shininess: 10}}\n",
                          "shapes[0].material.specular");
    expect_scene_rejected(sphere + "material: {albedo: 0.2, specular: 0.5}}\n",
                          "shapes[0].material");
    expect_scene_rejected(sphere + "material: {albedo: 0.2, specular: 0.5, shininess: 0.5}}\n",
                          "shapes[0].material.shininess");
    expect_scene_rejected(sphere + "material: {albedo: 0.2, specular: 0.5, shininess: 2e5}}\n",
                          "shapes[0].material.shininess");
    expect_scene_rejected(sphere + "material: {albedo: 0.2, specular: 0.5, roughness: 0.9}}\n",
                          "shapes[0].material.roughness");
    expect_scene_rejected(
        sphere + "material: {albedo: 0.2, specular: 0.5, shininess: 10, roughness: 0.1}}\n",
        "shapes[0].material.roughness");
    expect_scene_rejected(sphere + "material: {albedo: 0.2, shininess: 10}}\n",
                          "shapes[0].material.shininess");
    expect_scene_rejected(sphere + "material: {albedo: 0.6, specular: 0.5, shininess: 10}}\n",
                          "shapes[0].material.specular");
    expect_scene_rejected(sphere + "material: {albedo: 0.2, colour: red}}\n",
                          "shapes[0].material.colour");
    expect_scene_rejected(sphere + "material: {albedo: 0.2, specular: .nan, shininess: 10}}\n",
                          "shapes[0].material.specular");
    expect_scene_rejected(sphere + "material: 0.5}\n", "shapes[0].material");
    expect_scene_rejected(sphere + "albedo: 0.5, name: ''}\n", "shapes[0].name");
    expect_scene_rejected(sphere + "albedo: 0.5, name: [a, b]}\n", "shapes[0].name");
    // A checkerboard's albedos are its own fields; its lobe counts against the white one.
    const std::string board =
        "  - {type: checkerboard, centre: [0, 0, 500], inner_corners: [5, 4], "
        "square_size: 8, black_albedo: 0.05, white_albedo: 0.9, ";
    expect_scene_rejected(board + "material: {albedo: 0.5}}\n", "shapes[0].material.albedo");
    expect_scene_rejected(board + "material: {specular: 0.2, shininess: 10}}\n",
                          "shapes[0].material.specular");
    // The second shape's field is named.
    expect_scene_rejected(sphere + "albedo: 0.5}\n" + sphere +
                              "material: {albedo: 0.2, specular: 0.5, roughness: 0}}\n",
                          "shapes[1].material.roughness");
}

} // namespace
