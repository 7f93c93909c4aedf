// Evaluation figures on synthetic clouds with known answers: errors against
// the ground truth, cloud-to-cloud distances, guideline figures, the PLY to
// point-set conversion. (The report figures' drawing: test_plots.cpp.)

#include "test_support.hpp"

#include "fpp/calib/evaluation.hpp"
#include "fpp/error.hpp"
#include "fpp/lens_model.hpp"
#include "fpp/point_cloud.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace {

using fpp::Image;
using fpp::Mat3;
using fpp::mul;
using fpp::rotation_from_euler_deg;
using fpp::Size;
using fpp::transpose;
using fpp::Vec3;
using fpp::calib::CloudPoints;
using fpp::test::TempDir;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A tilted plane seen by a 40 x 30 pinhole camera (f = 800 px, centre 20, 15):
// X, Y, Z per pixel; columns 0..2 have no surface.
Image<float> truth_image() {
    Image<float> xyz(40, 30, 3, kNaN);
    for (int y = 0; y < 30; ++y)
        for (int x = 3; x < 40; ++x) {
            const double z = 500 + 0.5 * x + 0.25 * y;
            xyz.at(x, y, 0) = static_cast<float>((x - 20) * z / 800);
            xyz.at(x, y, 1) = static_cast<float>((y - 15) * z / 800);
            xyz.at(x, y, 2) = static_cast<float>(z);
        }
    return xyz;
}

TEST(Evaluation, TruthComparisonRecoversKnownOffset) {
    const Image<float> truth = truth_image();
    // Every true point moved 0.3 mm along its camera ray, away from the
    // camera; every 10th pixel left without a point; two points where the
    // truth has no surface.
    constexpr double kShift = 0.3;
    CloudPoints cloud;
    cloud.organised = {40, 30};
    double dz_sum = 0;
    std::size_t expected_compared = 0, truth_pixels = 0;
    for (int y = 0; y < 30; ++y)
        for (int x = 3; x < 40; ++x) {
            ++truth_pixels;
            const auto pixel = static_cast<std::uint32_t>(y * 40 + x);
            if (pixel % 10 == 0)
                continue;
            const double t[3] = {double(truth.at(x, y, 0)), double(truth.at(x, y, 1)),
                                 double(truth.at(x, y, 2))};
            const double n = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            const double k = 1 + kShift / n;
            cloud.points.push_back({t[0] * k, t[1] * k, t[2] * k});
            cloud.pixels.push_back(pixel);
            dz_sum += t[2] * (k - 1);
            ++expected_compared;
        }
    cloud.points.push_back({0, 0, 400});
    cloud.pixels.push_back(1);
    cloud.points.push_back({0, 0, 400});
    cloud.pixels.push_back(2 * 40 + 2);

    const auto t = fpp::calib::compare_with_truth(cloud, truth);
    EXPECT_EQ(t.truth_pixels, truth_pixels);
    EXPECT_EQ(t.compared, expected_compared);
    EXPECT_EQ(t.no_surface, 2u);
    EXPECT_DOUBLE_EQ(t.coverage, double(expected_compared) / double(truth_pixels));
    EXPECT_NEAR(t.distance.mean, kShift, 1e-9);
    EXPECT_NEAR(t.distance.rms, kShift, 1e-9);
    EXPECT_NEAR(t.distance.max, kShift, 1e-9);
    // Along the ray: Z moves by shift * Z / |P| (just under 0.3 mm here).
    EXPECT_NEAR(t.dz.mean, dz_sum / double(expected_compared), 1e-9);
    EXPECT_GT(t.dz.mean, 0.298);
    EXPECT_LT(t.dz.stddev, 1e-3);
    ASSERT_EQ(t.dz_values.size(), expected_compared);
    ASSERT_EQ(t.dz_map.size(), (Size{40, 30}));
    EXPECT_TRUE(std::isnan(t.dz_map.at(10, 0))); // pixel 10: no point
    EXPECT_TRUE(std::isnan(t.dz_map.at(1, 0)));  // no surface
    EXPECT_NEAR(t.dz_map.at(11, 0), t.dz_values[7], 1e-6);
}

TEST(Evaluation, TruthShapeErrorLeavesOutOffsetAndTilt) {
    // Z error = 0.4 mm + a tilt (0.002 X - 0.003 Y) + a bump of known RMS:
    // the shape error is the bump alone, its mean and tilt removed.
    const Image<float> truth = truth_image();
    CloudPoints cloud;
    cloud.organised = {40, 30};
    std::vector<double> bump;
    std::vector<std::array<double, 2>> xy;
    for (int y = 0; y < 30; ++y)
        for (int x = 3; x < 40; ++x) {
            const double X = truth.at(x, y, 0), Y = truth.at(x, y, 1), Z = truth.at(x, y, 2);
            const double b = 0.05 * std::cos(0.4 * x) * std::sin(0.3 * y);
            cloud.points.push_back({X, Y, Z + 0.4 + 0.002 * X - 0.003 * Y + b});
            cloud.pixels.push_back(static_cast<std::uint32_t>(y * 40 + x));
            bump.push_back(b);
            xy.push_back({X, Y});
        }
    // The bump's own least-squares plane in X, Y, by brute force in double.
    Eigen::MatrixXd a(static_cast<Eigen::Index>(bump.size()), 3);
    Eigen::VectorXd v(static_cast<Eigen::Index>(bump.size()));
    for (std::size_t i = 0; i < bump.size(); ++i) {
        a.row(static_cast<Eigen::Index>(i)) << 1.0, xy[i][0], xy[i][1];
        v[static_cast<Eigen::Index>(i)] = bump[i];
    }
    const Eigen::VectorXd residual = v - a * a.colPivHouseholderQr().solve(v);
    const double want = std::sqrt(residual.squaredNorm() / double(bump.size()));
    EXPECT_GT(want, 0.02);

    const auto t = fpp::calib::compare_with_truth(cloud, truth);
    EXPECT_GT(t.dz.rms, 0.39); // offset and tilt included
    EXPECT_NEAR(t.dz_shape.rms, want, 1e-5);
    EXPECT_NEAR(t.dz_shape.mean, 0.0, 1e-6);
    EXPECT_EQ(t.dz_shape.count, bump.size());
}

TEST(Evaluation, TruthAfterOneRigidMotionOfTheWholeCloud) {
    // The truth turned by 0.3 degrees about a far axis and shifted by
    // (0.2, -0.1, 0.5) mm, then given a bump of 0.01 mm along X on half the
    // pixels: the rigid motion found undoes the turn and shift (to the bump's
    // small pull on it), and what is left is the bump, not the motion.
    const Image<float> truth = truth_image();
    const Mat3 turn = rotation_from_euler_deg(0.1, 0.3, -0.2);
    const Vec3 shift{0.2, -0.1, 0.5};
    CloudPoints cloud;
    cloud.organised = {40, 30};
    for (int y = 0; y < 30; ++y)
        for (int x = 3; x < 40; ++x) {
            const Vec3 p = mul(turn, Vec3{double(truth.at(x, y, 0)), double(truth.at(x, y, 1)),
                                          double(truth.at(x, y, 2))});
            const double bump = (x + y) % 2 ? 0.01 : -0.01;
            cloud.points.push_back({p[0] + shift[0] + bump, p[1] + shift[1], p[2] + shift[2]});
            cloud.pixels.push_back(static_cast<std::uint32_t>(y * 40 + x));
        }
    const auto t = fpp::calib::compare_with_truth(cloud, truth);
    EXPECT_GT(t.distance.rms, 0.5); // the motion included
    EXPECT_NEAR(t.distance_rigid.rms, 0.01, 1e-4);
    EXPECT_NEAR(t.distance_rigid.max, 0.01, 2e-4);
    EXPECT_EQ(t.distance_rigid_values.size(), t.compared);
    // The motion found is the inverse of the one applied.
    const Mat3 back = transpose(turn);
    for (std::size_t i = 0; i < 9; ++i)
        EXPECT_NEAR(t.rigid_rotation[i], back[i], 1e-5) << i; // the bump pulls 1.5e-6
    const Vec3 undo = mul(back, shift);
    for (std::size_t i = 0; i < 3; ++i)
        EXPECT_NEAR(t.rigid_translation[i], -undo[i], 1e-3) << i;
    const double trace = turn[0] + turn[4] + turn[8];
    EXPECT_NEAR(t.rigid_angle_rad, std::acos((trace - 1) / 2), 1e-6);
}

TEST(Evaluation, TruthComparisonRejectsMismatches) {
    const Image<float> truth = truth_image();
    CloudPoints unorganised;
    unorganised.points = {{0, 0, 500}};
    EXPECT_THROW(fpp::calib::compare_with_truth(unorganised, truth), std::invalid_argument);
    CloudPoints other_size;
    other_size.organised = {20, 15};
    EXPECT_THROW(fpp::calib::compare_with_truth(other_size, truth), std::invalid_argument);
}

// An organised 60 x 40 cloud on a gently curved surface, 1 mm pixel pitch.
CloudPoints surface_cloud(const Vec3& shift = {0, 0, 0}, int skip_every = 0) {
    CloudPoints c;
    c.organised = {60, 40};
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 60; ++x) {
            const auto pixel = static_cast<std::uint32_t>(y * 60 + x);
            if (skip_every && pixel % static_cast<std::uint32_t>(skip_every) == 0)
                continue;
            c.points.push_back(
                {x + shift[0], y + shift[1], 500 + 0.002 * (x - 30) * (x - 30) + shift[2]});
            c.pixels.push_back(pixel);
        }
    return c;
}

TEST(Evaluation, PerPixelCloudToCloud) {
    const CloudPoints a = surface_cloud();
    const auto self = fpp::calib::compare_per_pixel(a, a);
    EXPECT_TRUE(self.per_pixel);
    EXPECT_EQ(self.matched, a.points.size());
    EXPECT_EQ(self.distance.rms, 0.0);
    EXPECT_EQ(self.dz.max_abs, 0.0);

    // A shifted copy with holes: the distance is the shift wherever both exist.
    const CloudPoints b = surface_cloud({0.03, -0.04, 0.12}, 7);
    const auto d = fpp::calib::compare_per_pixel(a, b);
    EXPECT_EQ(d.matched, b.points.size());
    EXPECT_EQ(d.only_first, a.points.size() - b.points.size());
    EXPECT_EQ(d.only_second, 0u);
    EXPECT_NEAR(d.distance.rms, 0.13, 1e-9);
    EXPECT_NEAR(d.distance.max, 0.13, 1e-9);
    EXPECT_NEAR(d.dz.mean, -0.12, 1e-9); // first - second
    EXPECT_NEAR(d.dz.stddev, 0.0, 1e-9);
    EXPECT_TRUE(std::isnan(d.dz_map.at(0, 0))); // pixel 0 skipped in b
    EXPECT_NEAR(d.dz_map.at(1, 0), -0.12, 1e-6);

    CloudPoints other_size = surface_cloud();
    other_size.organised = {30, 80};
    EXPECT_THROW(fpp::calib::compare_per_pixel(a, other_size), std::invalid_argument);
    CloudPoints unorganised = a;
    unorganised.organised = {};
    unorganised.pixels.clear();
    EXPECT_THROW(fpp::calib::compare_per_pixel(a, unorganised), std::invalid_argument);
}

TEST(Evaluation, NearestNeighbourCloudToCloud) {
    const CloudPoints a = surface_cloud();
    const auto self = fpp::calib::compare_nearest(a, a);
    EXPECT_FALSE(self.per_pixel);
    EXPECT_EQ(self.matched, a.points.size());
    EXPECT_EQ(self.distance.max, 0.0);
    // Shifted by 0.1 mm along Z: with a 1 mm pitch and a slope under 0.12,
    // each point's nearest neighbour is its own copy, about 0.1 mm away
    // (0.1 * cos(slope) from the surface, but the copy itself is 0.1 away).
    CloudPoints flat;
    for (int y = 0; y < 30; ++y)
        for (int x = 0; x < 30; ++x)
            flat.points.push_back({double(x), double(y), 500.0});
    CloudPoints lifted = flat;
    for (Vec3& p : lifted.points)
        p[2] += 0.1;
    const auto d = fpp::calib::compare_nearest(flat, lifted);
    EXPECT_EQ(d.matched, flat.points.size());
    EXPECT_NEAR(d.distance.rms, 0.1, 1e-12);
    EXPECT_NEAR(d.distance.min, 0.1, 1e-12);
    const auto none = fpp::calib::compare_nearest(flat, lifted, 0.05);
    EXPECT_EQ(none.matched, 0u);
    EXPECT_EQ(none.only_first, flat.points.size());
    EXPECT_THROW(fpp::calib::compare_nearest(flat, CloudPoints{}), std::invalid_argument);
}

TEST(Evaluation, CloudPointsFromPly) {
    TempDir dir;
    fpp::PointCloud cloud;
    cloud.xyz = Image<float>(8, 6, 3, kNaN);
    for (int x = 0; x < 8; ++x) {
        cloud.xyz.at(x, 2, 0) = static_cast<float>(x);
        cloud.xyz.at(x, 2, 1) = 2.0f;
        cloud.xyz.at(x, 2, 2) = 500.0f;
    }
    fpp::write_ply(dir / "c.ply", cloud);
    fpp::PlyPoints ply = fpp::read_ply(dir / "c.ply");
    const CloudPoints c = fpp::calib::cloud_points(ply, dir / "c.ply");
    EXPECT_TRUE(c.is_organised());
    EXPECT_EQ(c.organised, (Size{8, 6}));
    ASSERT_EQ(c.points.size(), 8u);
    EXPECT_EQ(c.pixels[3], 2u * 8u + 3u);
    EXPECT_EQ(c.points[3][0], 3.0);
    const CloudPoints direct = fpp::calib::cloud_points(cloud);
    EXPECT_EQ(direct.pixels, c.pixels);

    fpp::PlyPoints bad = ply;
    bad.pixel[5] = 48; // 8 x 6 = 48 pixels: out of range
    try {
        fpp::calib::cloud_points(bad, "bad.ply");
        FAIL() << "pixel index out of range accepted";
    } catch (const fpp::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.ply"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("vertex 5"), std::string::npos) << e.what();
    }
    bad.pixel[5] = bad.pixel[4];
    EXPECT_THROW(fpp::calib::cloud_points(bad, "bad.ply"), fpp::InputError);

    fpp::PlyPoints plain = ply;
    plain.pixel.clear();
    plain.x[0] = kNaN;
    const CloudPoints u = fpp::calib::cloud_points(plain, "plain.ply");
    EXPECT_FALSE(u.is_organised());
    EXPECT_EQ(u.points.size(), 7u); // the NaN vertex dropped
    EXPECT_TRUE(u.pixels.empty());
}

TEST(Evaluation, ErrorStatsAndCsv) {
    const std::vector<double> v = {1, -1, 3};
    const auto s = fpp::calib::error_stats(v);
    EXPECT_EQ(s.count, 3u);
    EXPECT_DOUBLE_EQ(s.mean, 1.0);
    EXPECT_DOUBLE_EQ(s.rms, std::sqrt(11.0 / 3));
    EXPECT_DOUBLE_EQ(s.stddev, std::sqrt(8.0 / 3));
    EXPECT_EQ(s.min, -1.0);
    EXPECT_EQ(s.max, 3.0);
    EXPECT_EQ(s.max_abs, 3.0);
    EXPECT_EQ(fpp::calib::error_stats({}).count, 0u);
    EXPECT_EQ(fpp::calib::figures_csv(
                  {{"cloud.fit.rms", 0.0501234567891, "mm"}, {"cloud.points", 12, ""}}),
              "name,value,unit\ncloud.fit.rms,0.0501234568,mm\ncloud.points,12,\n");
}

TEST(Evaluation, FlatnessExcludesTheGuidelineShare) {
    // 50 x 50 points, uniform noise within +-0.05 mm, 7 spikes of +-1 mm:
    // 0.3 % of 2500 is 7.5, so 7 points are excluded -> only the spikes.
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> noise(-0.05, 0.05);
    std::vector<Vec3> points;
    for (int y = 0; y < 50; ++y)
        for (int x = 0; x < 50; ++x)
            points.push_back({2.0 * x, 2.0 * y, 600 + 0.1 * x + noise(rng)});
    for (int k = 0; k < 7; ++k)
        points[static_cast<std::size_t>(k * 311 + 40)][2] += (k % 2 ? 1.0 : -1.0);
    const auto f = fpp::calib::flatness_figures(points);
    EXPECT_GT(f.flatness, 1.9);
    EXPECT_EQ(f.trimmed.excluded, 7u);
    EXPECT_LT(f.trimmed.range, 0.1 + 2e-3);
    EXPECT_GT(f.trimmed.range, 0.09);
    EXPECT_NEAR(f.trimmed.rms, 0.1 / std::sqrt(12.0), 0.003); // uniform noise
    EXPECT_DOUBLE_EQ(f.flatness, f.fit.fit.max - f.fit.fit.min);
}

TEST(Evaluation, ProbingAndSpacingFigures) {
    std::mt19937 rng(8);
    std::normal_distribution<double> n01;
    std::normal_distribution<double> noise(0, 0.01);
    // 2000 points on the side of a sphere facing a camera at the origin (-Z).
    auto cap = [&](const Vec3& c, double r) {
        std::vector<Vec3> out;
        while (out.size() < 2000) {
            const double d[3] = {n01(rng), n01(rng), n01(rng)};
            const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (d[2] / len > -0.3)
                continue;
            const double rr = r + noise(rng);
            out.push_back({c[0] + rr * d[0] / len, c[1] + rr * d[1] / len, c[2] + rr * d[2] / len});
        }
        return out;
    };
    const std::vector<Vec3> sphere = cap({0, 0, 600}, 12.5);
    const auto p = fpp::calib::probing_figures(sphere, 25.0);
    ASSERT_TRUE(p.size_error.has_value());
    EXPECT_DOUBLE_EQ(*p.size_error, p.diameter - 25.0);
    EXPECT_NEAR(p.diameter, 25.0, 0.006); // 5 x the Monte Carlo sigma, scaled to 0.01 mm noise
    EXPECT_DOUBLE_EQ(p.form, p.fit.fit.max - p.fit.fit.min);
    EXPECT_GT(p.form, 5.5 * 0.01); // range of 2000 Gaussian residuals: ~6.8 sigma
    EXPECT_LT(p.form, 10 * 0.01);
    EXPECT_EQ(p.form_trimmed.excluded, 6u);
    EXPECT_LT(p.form_trimmed.range, p.form);
    EXPECT_FALSE(fpp::calib::probing_figures(sphere, std::nullopt).size_error.has_value());

    std::vector<Vec3> bar = sphere;
    const std::vector<Vec3> second = cap({250, 0, 610}, 12.5);
    bar.insert(bar.end(), second.begin(), second.end());
    const double nominal = std::sqrt(250.0 * 250.0 + 10.0 * 10.0);
    const auto b = fpp::calib::ball_bar_figures(bar, nominal, 25.0);
    ASSERT_TRUE(b.spacing_error.has_value());
    EXPECT_NEAR(*b.spacing_error, 0.0, 0.01);
    EXPECT_DOUBLE_EQ(*b.spacing_error, b.length - nominal);
    EXPECT_NEAR(*b.size_error_first, 0.0, 0.006);
    EXPECT_NEAR(*b.size_error_second, 0.0, 0.006);
    EXPECT_EQ(b.cluster.size(), bar.size());
}

} // namespace
