// Finding a ball bar's spheres in a synthetic organised cloud: a pinhole
// camera (800 px focal length, 320 x 240) sees two spheres of 25.4 mm
// diameter at known centres in front of a wall at Z = 600 mm, the points
// ray-cast exactly (float storage is the only error). Also the usable-point
// mask (holes, depth jumps, the image border, the margin around them) and
// the hemisphere coverage on hand-made point sets.

#include "fpp/calib/artefact_search.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace {

using fpp::Image;
using fpp::Vec3;

constexpr int kWidth = 320, kHeight = 240;
constexpr double kFocal = 800, kCu = 159.5, kCv = 119.5;
constexpr double kDiameter = 25.4, kWallZ = 600;
const Vec3 kCentres[2] = {{-30, 5, 480}, {35, -8, 500}};

double dot(const Vec3& a, const Vec3& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// The nearest surface along pixel (u, v)'s ray: a sphere, else the wall.
Vec3 cast(int u, int v, const Vec3* centres, int spheres) {
    Vec3 d{(u - kCu) / kFocal, (v - kCv) / kFocal, 1};
    const double len = std::sqrt(dot(d, d));
    d = {d[0] / len, d[1] / len, d[2] / len};
    double t = kWallZ / d[2];
    const double r = kDiameter / 2;
    for (int s = 0; s < spheres; ++s) {
        const double b = dot(d, centres[s]);
        const double disc = b * b - dot(centres[s], centres[s]) + r * r;
        if (disc >= 0)
            t = std::min(t, b - std::sqrt(disc));
    }
    return {t * d[0], t * d[1], t * d[2]};
}

Image<float> scene(int spheres = 2) {
    Image<float> xyz(kWidth, kHeight, 3);
    for (int v = 0; v < kHeight; ++v)
        for (int u = 0; u < kWidth; ++u) {
            const Vec3 p = cast(u, v, kCentres, spheres);
            for (int c = 0; c < 3; ++c)
                xyz.at(u, v, c) = static_cast<float>(p[std::size_t(c)]);
        }
    return xyz;
}

// Pixel of a camera-frame point.
std::pair<int, int> pixel_of(const Vec3& p) {
    return {static_cast<int>(std::lround(kCu + kFocal * p[0] / p[2])),
            static_cast<int>(std::lround(kCv + kFocal * p[1] / p[2]))};
}

double distance(const Vec3& a, const Vec3& b) {
    const Vec3 d{a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return std::sqrt(dot(d, d));
}

TEST(UsablePoints, HolesJumpsBorderAndTheirMargin) {
    Image<float> xyz = scene();
    // A hole in the wall, far from the spheres.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (int c = 0; c < 3; ++c)
        xyz.at(280, 200, c) = nan;
    const std::vector<std::uint8_t> usable = fpp::calib::usable_points(xyz);
    ASSERT_EQ(usable.size(), std::size_t(kWidth * kHeight));
    const auto at = [&](int u, int v) { return usable[std::size_t(v * kWidth + u)]; };
    // The hole and the default 2 px margin about it.
    EXPECT_EQ(at(280, 200), 0);
    EXPECT_EQ(at(282, 200), 0);
    EXPECT_EQ(at(280, 198), 0);
    EXPECT_EQ(at(284, 200), 1);
    // The image border and its margin.
    EXPECT_EQ(at(0, 100), 0);
    EXPECT_EQ(at(2, 100), 0);
    EXPECT_EQ(at(4, 100), 1);
    EXPECT_EQ(at(100, kHeight - 1), 0);
    // The first sphere: its centre pixel usable, the wall just outside its
    // silhouette (a depth jump of about 110 mm) not, nor the sphere's rim.
    const auto [cu, cv] = pixel_of(kCentres[0]);
    const int radius_px = static_cast<int>(kFocal * kDiameter / 2 / kCentres[0][2]); // 21
    EXPECT_EQ(at(cu, cv), 1);
    EXPECT_EQ(at(cu + radius_px + 1, cv), 0);
    EXPECT_EQ(at(cu - radius_px, cv), 0);
    EXPECT_EQ(at(cu + radius_px + 6, cv), 1);
    // Counting: every usable pixel is finite; most of the image is usable.
    std::size_t count = 0;
    for (std::size_t i = 0; i < usable.size(); ++i) {
        count += usable[i];
        if (usable[i]) {
            EXPECT_TRUE(std::isfinite(xyz.data()[3 * i + 2])) << i;
        }
    }
    EXPECT_GT(count, usable.size() * 8 / 10);
    EXPECT_LT(count, usable.size());
}

TEST(UsablePoints, WiderMarginOption) {
    fpp::calib::ArtefactSearchOptions options;
    options.edge_margin_px = 5;
    const std::vector<std::uint8_t> usable = fpp::calib::usable_points(scene(), options);
    EXPECT_EQ(usable[std::size_t(100 * kWidth + 5)], 0);
    EXPECT_EQ(usable[std::size_t(100 * kWidth + 6)], 1);
}

TEST(FindSpheres, FindsBothSpheresOfABallBar) {
    const Image<float> xyz = scene();
    const std::vector<std::uint8_t> usable = fpp::calib::usable_points(xyz);
    const std::vector<fpp::calib::FoundSphere> found =
        fpp::calib::find_spheres(xyz, usable, kDiameter);
    ASSERT_EQ(found.size(), 2u);
    bool matched[2] = {false, false};
    for (const fpp::calib::FoundSphere& s : found) {
        const Vec3& c = s.figures.fit.centre;
        const int k = distance(c, kCentres[0]) < distance(c, kCentres[1]) ? 0 : 1;
        EXPECT_FALSE(matched[k]) << "two finds of sphere " << k;
        matched[k] = true;
        EXPECT_LT(distance(c, kCentres[k]), 1e-3) << k;
        EXPECT_NEAR(s.figures.diameter, kDiameter, 1e-3) << k;
        ASSERT_TRUE(s.figures.size_error.has_value());
        EXPECT_NEAR(*s.figures.size_error, 0, 1e-3) << k;
        EXPECT_LT(s.figures.form, 2e-3) << k;
        // Only sphere points are used: each on the certified shell.
        ASSERT_EQ(s.points.size(), s.pixels.size());
        EXPECT_GE(s.points.size(), 500u) << k;
        for (const Vec3& p : s.points)
            ASSERT_NEAR(distance(p, kCentres[k]), kDiameter / 2, 1e-3) << k;
        // A 42 px wide sphere: about half the facing hemisphere (header).
        EXPECT_GT(s.coverage, 0.35) << k;
        EXPECT_LT(s.coverage, 0.85) << k;
        EXPECT_GE(s.votes, 10u) << k;
    }
    // Strongest (most votes) first.
    EXPECT_GE(found[0].votes, found[1].votes);
}

TEST(FindSpheres, NoneOfAnotherDiameterNorOnAWallAlone) {
    const Image<float> xyz = scene();
    const std::vector<std::uint8_t> usable = fpp::calib::usable_points(xyz);
    EXPECT_TRUE(fpp::calib::find_spheres(xyz, usable, 50.8).empty());
    const Image<float> wall = scene(0);
    EXPECT_TRUE(fpp::calib::find_spheres(wall, fpp::calib::usable_points(wall), kDiameter).empty());
}

// Points on a sphere of radius 10 about `centre`: (theta, phi) grid.
std::vector<Vec3> shell(const Vec3& centre, int steps, double max_polar_deg, bool facing) {
    std::vector<Vec3> points;
    const double len = std::sqrt(dot(centre, centre));
    const Vec3 view{-centre[0] / len, -centre[1] / len, -centre[2] / len}; // to the camera
    constexpr double kPi = 3.14159265358979323846;
    for (int i = 0; i <= steps; ++i)
        for (int j = 0; j < 4 * steps; ++j) {
            const double polar = max_polar_deg * kPi / 180 * i / steps;
            const double azimuth = 2 * kPi * j / (4 * steps);
            // centre on the Z axis in these tests: view = (0, 0, -1)
            const Vec3 u{std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth),
                         std::cos(polar) * (facing ? view[2] : -view[2])};
            points.push_back({centre[0] + 10 * u[0], centre[1] + 10 * u[1], centre[2] + 10 * u[2]});
        }
    return points;
}

TEST(HemisphereCoverage, CountsCellsOfTheFacingHemisphere) {
    const Vec3 centre{0, 0, 500};
    // Densely over the whole facing hemisphere: every one of the 156 cells.
    EXPECT_DOUBLE_EQ(fpp::calib::hemisphere_coverage(shell(centre, 200, 90, true), centre), 1.0);
    // The far hemisphere only: none.
    EXPECT_DOUBLE_EQ(fpp::calib::hemisphere_coverage(shell(centre, 200, 89, false), centre), 0.0);
    // One point, the one nearest the camera: one cell of 156.
    const std::vector<Vec3> one{{0, 0, 490}};
    EXPECT_DOUBLE_EQ(fpp::calib::hemisphere_coverage(one, centre), 1.0 / 156);
    // Up to 60 degrees from the view direction: the equal-area map makes
    // it (1 - cos 60) = half the hemisphere's area, give or take the cells
    // the rim cuts.
    const double cap = fpp::calib::hemisphere_coverage(shell(centre, 200, 60, true), centre);
    EXPECT_GT(cap, 0.45);
    EXPECT_LT(cap, 0.6);
    EXPECT_EQ(fpp::calib::hemisphere_coverage({}, centre), 0.0);
}

} // namespace
