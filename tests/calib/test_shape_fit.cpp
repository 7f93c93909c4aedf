// Shape fits on synthetic points with known truth and Gaussian noise.
//
// Tolerances are 5 standard deviations of the parameter's estimation error
// for the noise and sampling used, measured by Monte Carlo (100 trials for
// plane and sphere, 60 for the cylinder) and, where a closed form exists,
// checked against it:
//   plane, 5000 points on 100 x 100 mm, sigma 0.05 mm: tilt per axis
//     sigma / (sqrt(N) * 100 / sqrt(12)) = 2.4e-5 rad (Monte Carlo: 3.9e-5 rad
//     for the total angle of two axes), offset sigma / sqrt(N) = 7.1e-4 mm
//     -> angle 2e-4 rad, offset 3.5e-3 mm;
//   sphere, R 12.7 mm, 4000 points on a cap of 70 deg half-angle, sigma
//     0.02 mm: centre 2.0e-3 mm, radius 1.2e-3 mm -> centre 0.01 mm, radius
//     0.006 mm;
//   cylinder, R 84 mm (the paper's 168 mm pipe), 90 deg of arc, 150 mm long,
//     6000 points, sigma 0.05 mm: axis 3.6e-5 rad, radius 5.5e-3 mm, axis
//     position 6.1e-3 mm -> axis 2e-4 rad, radius 0.03 mm, position 0.03 mm.
// The residual RMS must match sigma within 10 %.

#include "fpp/calib/shape_fit.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

namespace {

using Eigen::Vector3d;
using fpp::Vec3;
using fpp::calib::FitError;
using fpp::calib::FitOptions;

constexpr double kPi = 3.14159265358979323846;

Vec3 vec(const Vector3d& v) {
    return {v.x(), v.y(), v.z()};
}
Vector3d eig(const Vec3& v) {
    return {v[0], v[1], v[2]};
}

Vector3d random_unit(std::mt19937& rng) {
    std::normal_distribution<double> n;
    return Vector3d(n(rng), n(rng), n(rng)).normalized();
}

double angle_between_lines(const Vector3d& a, const Vector3d& b) {
    return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized()))));
}

// ---------------------------------------------------------------- plane

struct PlaneTruth {
    Vector3d point, normal;
    std::vector<Vec3> points;
};

PlaneTruth noisy_plane(unsigned seed, std::size_t n, double sigma) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0, sigma);
    std::uniform_real_distribution<double> u(-50, 50);
    PlaneTruth t;
    t.normal = random_unit(rng);
    if (t.normal.z() > 0)
        t.normal = -t.normal; // facing the camera
    t.point = Vector3d(10, -20, 800);
    const Vector3d a = t.normal.unitOrthogonal(), b = t.normal.cross(a);
    for (std::size_t i = 0; i < n; ++i)
        t.points.push_back(vec(t.point + u(rng) * a + u(rng) * b + noise(rng) * t.normal));
    return t;
}

TEST(ShapeFit, PlaneRecoversNormalOffsetAndNoise) {
    for (unsigned seed : {1u, 2u, 3u}) {
        const PlaneTruth t = noisy_plane(seed, 5000, 0.05);
        const auto f = fpp::calib::fit_plane(t.points);
        EXPECT_LT(angle_between_lines(eig(f.normal), t.normal), 2e-4) << "seed " << seed;
        EXPECT_NEAR((eig(f.point) - t.point).dot(t.normal), 0.0, 3.5e-3);
        EXPECT_NEAR(f.fit.rms, 0.05, 0.005);
        EXPECT_EQ(f.fit.used, 5000u);
        EXPECT_EQ(f.fit.rejected, 0u);
        ASSERT_EQ(f.fit.residuals.size(), 5000u);
        // Normal towards the camera: positive residual = nearer the camera.
        EXPECT_LT(eig(f.normal).dot(eig(f.point)), 0.0);
        const double rms_check =
            std::sqrt(std::inner_product(f.fit.residuals.begin(), f.fit.residuals.end(),
                                         f.fit.residuals.begin(), 0.0) /
                      5000.0);
        EXPECT_NEAR(rms_check, f.fit.rms, 1e-12);
        EXPECT_LT(f.fit.min, -3 * 0.05);
        EXPECT_GT(f.fit.max, 3 * 0.05);
        EXPECT_NE(f.fit.message.find("plane"), std::string::npos);
    }
}

TEST(ShapeFit, PlaneSignedResidualPositiveTowardsCamera) {
    // 11 x 11 grid; its centre point 1 mm nearer the camera leaves the plane
    // level (no moment) and moves it 1/121 mm towards the camera.
    std::vector<Vec3> points;
    for (int i = -5; i <= 5; ++i)
        for (int j = -5; j <= 5; ++j)
            points.push_back({double(i), double(j), 500.0});
    points[60][2] = 499.0;
    const auto f = fpp::calib::fit_plane(points);
    EXPECT_NEAR(f.normal[2], -1.0, 1e-12);
    EXPECT_NEAR(f.fit.residuals[60], 1 - 1.0 / 121, 1e-9);
    EXPECT_NEAR(f.fit.residuals[0], -1.0 / 121, 1e-9);
    EXPECT_NEAR(f.fit.max, 1 - 1.0 / 121, 1e-9);
    EXPECT_NEAR(f.fit.min, -1.0 / 121, 1e-9);
}

TEST(ShapeFit, PlaneFarFromOriginStaysAccurate) {
    // Conditioning: a tiny noise-free tilt 2 m away is still found exactly.
    std::vector<Vec3> points;
    for (int i = 0; i < 20; ++i)
        for (int j = 0; j < 20; ++j)
            points.push_back({1000.0 + i, 2000.0 + j, 2000.0 + 1e-4 * i});
    const auto f = fpp::calib::fit_plane(points);
    const Vector3d expected = Vector3d(-1e-4, 0, 1).normalized();
    EXPECT_LT(angle_between_lines(eig(f.normal), expected), 1e-9);
    EXPECT_LT(f.fit.rms, 1e-9);
}

TEST(ShapeFit, PlaneRejectsDegenerateInput) {
    EXPECT_THROW(fpp::calib::fit_plane(std::vector<Vec3>{{0, 0, 1}, {1, 0, 1}}), FitError);
    std::vector<Vec3> line;
    for (int i = 0; i < 50; ++i)
        line.push_back({double(i), 2.0 * i, 100.0 + i});
    try {
        fpp::calib::fit_plane(line);
        FAIL() << "collinear points accepted";
    } catch (const FitError& e) {
        EXPECT_NE(std::string(e.what()).find("collinear"), std::string::npos) << e.what();
    }
    std::vector<Vec3> same(10, Vec3{1, 2, 3});
    EXPECT_THROW(fpp::calib::fit_plane(same), FitError);
    std::vector<Vec3> bad = noisy_plane(4, 100, 0.01).points;
    bad[17][1] = std::numeric_limits<double>::quiet_NaN();
    try {
        fpp::calib::fit_plane(bad);
        FAIL() << "NaN accepted";
    } catch (const FitError& e) {
        EXPECT_NE(std::string(e.what()).find("point 17"), std::string::npos) << e.what();
    }
}

TEST(ShapeFit, PlaneOutlierRejectionRemovesSpikes) {
    PlaneTruth t = noisy_plane(7, 4000, 0.05);
    std::mt19937 rng(99);
    std::uniform_int_distribution<std::size_t> pick(0, t.points.size() - 1);
    std::uniform_real_distribution<double> height(1.0, 5.0);
    std::vector<std::size_t> spikes;
    while (spikes.size() < 40) {
        const std::size_t i = pick(rng);
        if (std::find(spikes.begin(), spikes.end(), i) != spikes.end())
            continue;
        spikes.push_back(i);
        const double h = (spikes.size() % 2 ? 1 : -1) * height(rng);
        t.points[i] = vec(eig(t.points[i]) + h * t.normal);
    }
    const auto plain = fpp::calib::fit_plane(t.points);
    EXPECT_GT(plain.fit.rms, 0.25); // the spikes dominate
    FitOptions robust;
    robust.reject_sigma = 3;
    const auto f = fpp::calib::fit_plane(t.points, robust);
    for (std::size_t i : spikes)
        EXPECT_EQ(f.fit.inlier[i], 0) << "spike " << i << " kept";
    EXPECT_GE(f.fit.rejected, spikes.size());
    // Only a few Gaussian tail points (beyond ~3 sigma: 0.3 %) go with them.
    EXPECT_LT(f.fit.rejected, spikes.size() + 40);
    EXPECT_GT(f.fit.rejection_rounds, 0);
    EXPECT_NEAR(f.fit.rms, 0.05, 0.005);
    EXPECT_LT(angle_between_lines(eig(f.normal), t.normal), 2e-4);
    EXPECT_NE(f.fit.message.find("rejected at 3.0 sigma"), std::string::npos) << f.fit.message;
}

// ---------------------------------------------------------------- sphere

struct SphereTruth {
    Vector3d centre;
    double radius;
    std::vector<Vec3> points;
};

// The cap a camera at the origin sees, up to `half_angle_deg` from the view direction.
SphereTruth noisy_sphere(unsigned seed, Vector3d centre, double radius, std::size_t n, double sigma,
                         double half_angle_deg = 70) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0, sigma);
    SphereTruth t{centre, radius, {}};
    const Vector3d view = -centre.normalized();
    while (t.points.size() < n) {
        const Vector3d d = random_unit(rng);
        if (d.dot(view) < std::cos(half_angle_deg * kPi / 180))
            continue;
        t.points.push_back(vec(centre + (radius + noise(rng)) * d));
    }
    return t;
}

TEST(ShapeFit, SphereRecoversCentreRadiusAndNoise) {
    for (unsigned seed : {11u, 12u, 13u}) {
        const SphereTruth t = noisy_sphere(seed, {30, -10, 700}, 12.7, 4000, 0.02);
        const auto f = fpp::calib::fit_sphere(t.points);
        EXPECT_LT((eig(f.centre) - t.centre).norm(), 0.01) << "seed " << seed;
        EXPECT_NEAR(f.radius, 12.7, 0.006);
        EXPECT_NEAR(f.fit.rms, 0.02, 0.002);
        EXPECT_GT(f.fit.iterations, 0);
        // Residual sign: a point pushed outwards has a positive residual.
        EXPECT_NEAR(f.fit.residuals[0], (eig(t.points[0]) - eig(f.centre)).norm() - f.radius,
                    1e-12);
    }
}

TEST(ShapeFit, SphereRejectsDegenerateInput) {
    EXPECT_THROW(fpp::calib::fit_sphere(std::vector<Vec3>{{0, 0, 1}, {1, 0, 1}, {0, 1, 1}}),
                 FitError);
    // A circle in a plane: no sphere is determined.
    std::vector<Vec3> circle;
    for (int i = 0; i < 60; ++i)
        circle.push_back({10 * std::cos(i * 0.1), 10 * std::sin(i * 0.1), 500.0});
    EXPECT_THROW(fpp::calib::fit_sphere(circle), FitError);
    // A noisy flat patch: no curvature.
    try {
        fpp::calib::fit_sphere(noisy_plane(5, 2000, 1e-4).points);
        FAIL() << "flat patch accepted as a sphere";
    } catch (const FitError& e) {
        EXPECT_NE(std::string(e.what()).find("sphere fit"), std::string::npos) << e.what();
    }
}

TEST(ShapeFit, SphereOutlierRejectionRemovesSpikes) {
    SphereTruth t = noisy_sphere(21, {0, 0, 600}, 12.7, 3000, 0.02);
    for (std::size_t i = 0; i < 30; ++i) {
        const std::size_t k = i * 97;
        const Vector3d p = eig(t.points[k]);
        t.points[k] = vec(p + (i % 2 ? 0.5 : -0.5) * (p - t.centre).normalized());
    }
    FitOptions robust;
    robust.reject_sigma = 3;
    const auto f = fpp::calib::fit_sphere(t.points, robust);
    for (std::size_t i = 0; i < 30; ++i)
        EXPECT_EQ(f.fit.inlier[i * 97], 0);
    EXPECT_NEAR(f.fit.rms, 0.02, 0.002);
    EXPECT_NEAR(f.radius, 12.7, 0.006);
}

// ---------------------------------------------------------------- cylinder

struct CylinderTruth {
    Vector3d point, axis;
    double radius;
    std::vector<Vec3> points;
};

// The part of a cylinder a camera at the origin sees: `arc_deg` of arc
// centred on the side facing the camera, `length` long, random axis (at
// least 30 deg away from the viewing direction).
CylinderTruth noisy_cylinder(unsigned seed, double radius, double arc_deg, double length,
                             std::size_t n, double sigma) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0, sigma);
    std::uniform_real_distribution<double> along(-length / 2, length / 2);
    std::uniform_real_distribution<double> angle(-arc_deg / 2 * kPi / 180, arc_deg / 2 * kPi / 180);
    CylinderTruth t;
    t.point = Vector3d(20, 10, 650);
    t.radius = radius;
    const Vector3d view = -t.point.normalized();
    do
        t.axis = random_unit(rng);
    while (std::abs(t.axis.dot(view)) > std::cos(30 * kPi / 180));
    const Vector3d u = (view - view.dot(t.axis) * t.axis).normalized(), v = t.axis.cross(u);
    for (std::size_t i = 0; i < n; ++i) {
        const double th = angle(rng);
        t.points.push_back(vec(t.point + along(rng) * t.axis +
                               (radius + noise(rng)) * (std::cos(th) * u + std::sin(th) * v)));
    }
    return t;
}

double axis_offset(const fpp::calib::CylinderFit& f, const CylinderTruth& t) {
    const Vector3d d = eig(f.axis_point) - t.point;
    return (d - d.dot(t.axis) * t.axis).norm();
}

TEST(ShapeFit, CylinderPartialArcRandomAxes) {
    for (unsigned seed : {31u, 32u, 33u, 34u, 35u}) {
        const CylinderTruth t = noisy_cylinder(seed, 84, 90, 150, 6000, 0.05);
        const auto f = fpp::calib::fit_cylinder(t.points);
        EXPECT_LT(angle_between_lines(eig(f.axis), t.axis), 2e-4) << "seed " << seed;
        EXPECT_NEAR(f.radius, 84, 0.03) << "seed " << seed;
        EXPECT_LT(axis_offset(f, t), 0.03) << "seed " << seed;
        EXPECT_NEAR(f.fit.rms, 0.05, 0.005);
        EXPECT_NEAR(f.arc_degrees, 90, 1.0);
        EXPECT_NEAR(f.length, 150, 1.0);
    }
}

TEST(ShapeFit, CylinderShortWideArcAndTwoSidedNoise) {
    // Shorter than its chord (the principal direction is across the axis)
    // and 120 deg of arc: the normal-based start must carry it.
    const CylinderTruth t = noisy_cylinder(41, 84, 120, 40, 5000, 0.1);
    const auto f = fpp::calib::fit_cylinder(t.points);
    EXPECT_LT(angle_between_lines(eig(f.axis), t.axis), 2e-3);
    EXPECT_NEAR(f.radius, 84, 0.05);
    EXPECT_NEAR(f.fit.rms, 0.1, 0.01);
    EXPECT_NEAR(f.arc_degrees, 120, 1.5);
}

TEST(ShapeFit, CylinderRejectsDegenerateInput) {
    EXPECT_THROW(fpp::calib::fit_cylinder(std::vector<Vec3>{{0, 0, 1}, {1, 0, 1}, {0, 1, 1}}),
                 FitError);
    std::vector<Vec3> line;
    for (int i = 0; i < 50; ++i)
        line.push_back({double(i), 0.0, 300.0});
    EXPECT_THROW(fpp::calib::fit_cylinder(line), FitError);
    try {
        fpp::calib::fit_cylinder(noisy_plane(6, 3000, 1e-4).points);
        FAIL() << "flat patch accepted as a cylinder";
    } catch (const FitError& e) {
        EXPECT_NE(std::string(e.what()).find("cylinder fit"), std::string::npos) << e.what();
    }
}

TEST(ShapeFit, CylinderOutlierRejection) {
    CylinderTruth t = noisy_cylinder(51, 84, 100, 120, 5000, 0.05);
    for (std::size_t i = 0; i < 50; ++i)
        t.points[i * 100][2] += (i % 2 ? 2.0 : -2.0);
    FitOptions robust;
    robust.reject_sigma = 3;
    const auto f = fpp::calib::fit_cylinder(t.points, robust);
    for (std::size_t i = 0; i < 50; ++i)
        EXPECT_EQ(f.fit.inlier[i * 100], 0);
    EXPECT_NEAR(f.fit.rms, 0.05, 0.005);
    EXPECT_NEAR(f.radius, 84, 0.03);
}

// ---------------------------------------------------------------- ball-bar

TEST(ShapeFit, BallBarCentreDistance) {
    // Two 25.4 mm balls 300 mm apart; sphere sigma as above, so each centre
    // is good to 0.01 mm and the distance to 0.015 mm (root-sum-square).
    const Vector3d a(-150, 20, 700), b(150, -20, 720);
    const double nominal = (a - b).norm();
    const SphereTruth first = noisy_sphere(61, a, 12.7, 3000, 0.02);
    const SphereTruth second = noisy_sphere(62, b, 12.7, 3000, 0.02);
    const auto separate = fpp::calib::fit_ball_bar(first.points, second.points);
    EXPECT_NEAR(separate.distance, nominal, 0.015);
    EXPECT_NEAR(separate.first.radius, 12.7, 0.006);
    EXPECT_NEAR(separate.second.radius, 12.7, 0.006);

    // One cloud, with part of the bar between the balls scanned too.
    std::vector<Vec3> all = first.points;
    all.insert(all.end(), second.points.begin(), second.points.end());
    for (int i = 0; i < 60; ++i) {
        const double s = 0.06 + 0.0015 * i; // near the first ball
        all.push_back(vec(a + s * (b - a) + Vector3d(0, 0, -4)));
        all.push_back(vec(b + s * (a - b) + Vector3d(0, 0, -4)));
    }
    FitOptions robust;
    robust.reject_sigma = 3;
    std::vector<std::uint8_t> cluster;
    const auto joint = fpp::calib::fit_ball_bar(all, robust, &cluster);
    EXPECT_NEAR(joint.distance, nominal, 0.015);
    ASSERT_EQ(cluster.size(), all.size());
    for (std::size_t i = 0; i < first.points.size(); ++i)
        ASSERT_EQ(cluster[i], cluster[0]);
    for (std::size_t i = 0; i < second.points.size(); ++i)
        ASSERT_NE(cluster[first.points.size() + i], cluster[0]);
    EXPECT_GE(joint.first.fit.rejected + joint.second.fit.rejected, 120u);
    EXPECT_NEAR(joint.first.fit.rms, 0.02, 0.002);
    EXPECT_NEAR(joint.second.fit.rms, 0.02, 0.002);
}

TEST(ShapeFit, BallBarNamesTheFailingSphere) {
    const SphereTruth first = noisy_sphere(71, {0, 0, 700}, 12.7, 500, 0.02);
    std::vector<Vec3> few = {{100, 0, 700}, {101, 0, 700}};
    try {
        fpp::calib::fit_ball_bar(first.points, few);
        FAIL();
    } catch (const FitError& e) {
        EXPECT_NE(std::string(e.what()).find("second sphere"), std::string::npos) << e.what();
    }
}

// ---------------------------------------------------------------- k-d tree

TEST(PointIndex, MatchesBruteForce) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-100, 100);
    std::vector<Vec3> points(3000);
    for (Vec3& p : points)
        p = {u(rng), u(rng), 0.1 * u(rng)};
    const fpp::calib::PointIndex index(points);
    std::vector<std::pair<double, std::size_t>> near;
    for (int q = 0; q < 200; ++q) {
        const Vec3 query = {u(rng), u(rng), u(rng)};
        std::vector<std::pair<double, std::size_t>> brute;
        for (std::size_t i = 0; i < points.size(); ++i) {
            const double dx = points[i][0] - query[0], dy = points[i][1] - query[1],
                         dz = points[i][2] - query[2];
            brute.emplace_back(dx * dx + dy * dy + dz * dz, i);
        }
        std::sort(brute.begin(), brute.end());
        double d2 = -1;
        EXPECT_EQ(index.nearest(query, &d2), brute[0].second);
        EXPECT_EQ(d2, brute[0].first);
        index.nearest_k(query, 7, near);
        ASSERT_EQ(near.size(), 7u);
        for (std::size_t k = 0; k < 7; ++k)
            EXPECT_EQ(near[k].second, brute[k].second);
    }
    const fpp::calib::PointIndex empty(std::vector<Vec3>{});
    EXPECT_EQ(empty.nearest({0, 0, 0}), 0u);
}

} // namespace
