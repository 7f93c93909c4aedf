// Verification with a certified artefact (fpp/calib/verification.hpp,
// artefact_search.hpp) on the virtual scanner's true surfaces (the paper rig,
// camera binned 4x, points where the projector lights them, noise added
// along each ray): the ball bar found among its rod, its stand and a wall;
// spheres cut by the view's edge or holed by a highlight; the refusals (a
// sphere missing, one too many, spheres overlapping in view, too little
// surface, a certificate the scans contradict); a plate before a wall; the
// verdicts. The whole path from frames through a table: tests/cli/test_cli_verify.cpp.

#include "test_support.hpp"

#include "fpp/calib/artefact.hpp"
#include "fpp/calib/artefact_search.hpp"
#include "fpp/calib/verification.hpp"
#include "fpp/error.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>

namespace {

using fpp::Image;
using fpp::Vec3;
using fpp::calib::Artefact;
using fpp::calib::ArtefactKind;
using fpp::calib::MeasuredPosition;
using fpp::calib::VerificationOptions;
namespace sim = fpp::sim;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kLength = 150, kDiameter = 30;

sim::Rig small_rig() {
    return sim::Rig::paper().binned_camera(4); // 400 x 300
}

Vec3 along(const Vec3& centre, const Vec3& axis, double t) {
    const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    return {centre[0] + t * axis[0] / n, centre[1] + t * axis[1] / n, centre[2] + t * axis[2] / n};
}

double distance(const Vec3& a, const Vec3& b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                     (a[2] - b[2]) * (a[2] - b[2]));
}

// A ball bar (two 30 mm spheres 150 mm apart), with its 10 mm rod, a post
// under it and a wall behind when `surroundings`.
sim::Scene bar_scene(const Vec3& centre, const Vec3& axis, bool surroundings,
                     double length = kLength) {
    sim::Scene scene;
    sim::add_ball_bar(scene, centre, axis, length, kDiameter / 2, 0.85, "ball");
    if (surroundings) {
        scene.add(std::make_unique<sim::Cylinder>(centre, axis, 5, length - 28, 0.6), "rod");
        scene.add(std::make_unique<sim::Cylinder>(Vec3{centre[0], centre[1] + 65, centre[2] + 5},
                                                  Vec3{0, 1, 0}, 8, 120, 0.7),
                  "stand");
        scene.add(std::make_unique<sim::Plane>(sim::Pose{{0, 0, 575}, {1, 0, 0, 0, 1, 0, 0, 0, 1}},
                                               420, 330, 0.8),
                  "wall");
    }
    return scene;
}

struct Scan {
    Image<float> xyz;   // with noise, where the projector lights a surface
    Image<float> truth; // the true points there
};

// The points the camera sees and the projector lights, each moved along its
// ray by N(0, noise_mm).
Scan scan_of(const sim::Scene& scene, double noise_mm, unsigned seed = 1) {
    const sim::Renderer renderer(small_rig(), scene);
    Scan s;
    s.truth = renderer.truth_xyz();
    const Image<float>& lit = renderer.truth_projector();
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0, noise_mm);
    for (std::size_t i = 0; i < s.truth.pixel_count(); ++i) {
        float* p = s.truth.data() + 3 * i;
        if (!std::isfinite(lit.data()[2 * i]))
            p[0] = p[1] = p[2] = static_cast<float>(kNaN);
    }
    s.xyz = s.truth;
    for (std::size_t i = 0; i < s.xyz.pixel_count(); ++i) {
        float* p = s.xyz.data() + 3 * i;
        if (!std::isfinite(p[2]))
            continue;
        const double x = double(p[0]), y = double(p[1]), z = double(p[2]);
        const double r = std::sqrt(x * x + y * y + z * z);
        const double f = 1 + (noise_mm > 0 ? noise(rng) : 0.0) / r;
        for (int c = 0; c < 3; ++c)
            p[c] = static_cast<float>(double(p[c]) * f);
    }
    return s;
}

Artefact ball_bar(double length = kLength, double diameter = kDiameter) {
    Artefact a;
    a.origin = "bar.yaml";
    a.kind = ArtefactKind::ball_bar;
    a.sphere_diameters_mm = {diameter, diameter};
    a.centre_distance_mm = length;
    a.uncertainty_mm = 0.001;
    return a;
}

// The camera frame X of the image's right edge at depth z.
double right_edge_x(double z) {
    const sim::Rig rig = small_rig();
    fpp::Vec2 n{};
    EXPECT_TRUE(rig.camera.pixel_to_normalised({rig.camera_size.width - 0.5, rig.camera.cv}, n));
    return n[0] * z;
}

// The refusal measure_position gives.
fpp::InputError refusal(const Artefact& artefact, const Scan& scan) {
    try {
        fpp::calib::measure_position(artefact, scan.xyz, "position-1", VerificationOptions{});
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), std::filesystem::path("position-1"));
        return e;
    }
    ADD_FAILURE() << "measured";
    return fpp::InputError("", "", "");
}

bool says(const fpp::InputError& e, const std::string& part) {
    return std::string(e.what()).find(part) != std::string::npos;
}

TEST(Verification, FindsTheBallBarAmongItsRodStandAndWall) {
    const Vec3 centre{0, -10, 480}, axis{1, 0, 0.25};
    const Scan scan = scan_of(bar_scene(centre, axis, true), 0.02);
    const MeasuredPosition m = fpp::calib::measure_position(ball_bar(), scan.xyz, "position-1",
                                                            VerificationOptions{}, scan.truth);
    ASSERT_EQ(m.spheres.size(), 2u);
    // Sphere 1 is the one further left (smaller X).
    EXPECT_LT(distance(m.spheres[0].centre, along(centre, axis, -75)), 0.01);
    EXPECT_LT(distance(m.spheres[1].centre, along(centre, axis, 75)), 0.01);
    ASSERT_TRUE(m.spacing_error && m.truth_spacing_error);
    EXPECT_NEAR(*m.spacing_error, 0, 0.005);
    EXPECT_NEAR(*m.truth_spacing_error, 0, 1e-4); // exact points: exact centres
    for (const auto& s : m.spheres) {
        EXPECT_GT(s.coverage, 0.4) << s.index;
        EXPECT_GT(s.points_used, 500u) << s.index;
        EXPECT_NEAR(s.size_error, 0, 0.01) << s.index;
        EXPECT_LT(s.form, 0.2) << s.index; // noise 0.02: about 8 sigma
        EXPECT_LT(s.rms, 0.025) << s.index;
    }
}

// Half of sphere 2 in view: its centre on the image's right edge.
Scan half_in_view() {
    const double z = 480;
    return scan_of(bar_scene({right_edge_x(z) - 75, 0, z}, {1, 0, 0}, false), 0.02);
}

TEST(Verification, FitsASphereCutByTheEdgeOfTheViewFromWhatIsThere) {
    const double z = 480;
    const Vec3 centre{right_edge_x(z) - 75, 0, z};
    VerificationOptions options;
    options.min_coverage = 0.15;
    const MeasuredPosition m =
        fpp::calib::measure_position(ball_bar(), half_in_view().xyz, "position-1", options);
    ASSERT_EQ(m.spheres.size(), 2u);
    const auto &whole = m.spheres[0], &cut = m.spheres[1];
    EXPECT_LT(cut.coverage, 0.6 * whole.coverage);
    EXPECT_GT(cut.coverage, 0.15);
    EXPECT_LT(distance(cut.centre, along(centre, {1, 0, 0}, 75)), 0.03);
    EXPECT_NEAR(*m.spacing_error, 0, 0.03);
}

TEST(Verification, RefusesASphereWithTooLittleSurfaceNamingIt) {
    // At 42 px across, half a sphere covers about 0.22 of its hemisphere:
    // under the default minimum (0.25).
    const fpp::InputError e = refusal(ball_bar(), half_in_view());
    EXPECT_EQ(e.field(), "sphere 2") << e.what();
    EXPECT_TRUE(says(e, "too little of the sphere's surface")) << e.what();
}

TEST(Verification, FitsASphereHalfOutOfTheProjectorsLight) {
    const Vec3 centre{0, -10, 480}, axis{1, 0, 0.25};
    Scan scan = scan_of(bar_scene(centre, axis, true), 0.02);
    // The edge of the projector's image (or the stand's shadow) across
    // sphere 2: nothing decodes beyond it.
    const Vec3 c2 = along(centre, axis, 75);
    for (std::size_t i = 0; i < scan.xyz.pixel_count(); ++i) {
        float* p = scan.xyz.data() + 3 * i;
        if (std::isfinite(p[2]) && double(p[0]) > c2[0] && double(p[0]) < c2[0] + 20)
            p[0] = p[1] = p[2] = static_cast<float>(kNaN);
    }
    VerificationOptions options;
    options.min_coverage = 0.15;
    const MeasuredPosition m =
        fpp::calib::measure_position(ball_bar(), scan.xyz, "position-1", options);
    ASSERT_EQ(m.spheres.size(), 2u);
    EXPECT_LT(m.spheres[1].coverage, 0.6 * m.spheres[0].coverage);
    EXPECT_LT(distance(m.spheres[1].centre, c2), 0.03);
    EXPECT_NEAR(*m.spacing_error, 0, 0.03);
}

TEST(Verification, FitsASphereWithAHighlightHole) {
    const Vec3 centre{0, -10, 480}, axis{1, 0, 0.25};
    Scan scan = scan_of(bar_scene(centre, axis, true), 0.02);
    const MeasuredPosition whole =
        fpp::calib::measure_position(ball_bar(), scan.xyz, "position-1", VerificationOptions{});
    // A saturated highlight decodes to nothing: a 12 mm wide hole in the
    // front of sphere 2, where the projector's light comes back.
    const Vec3 c2 = along(centre, axis, 75);
    for (std::size_t i = 0; i < scan.xyz.pixel_count(); ++i) {
        float* p = scan.xyz.data() + 3 * i;
        const Vec3 point{double(p[0]), double(p[1]), double(p[2])};
        const Vec3 front = {c2[0] + 5, c2[1], c2[2] - 14};
        if (std::isfinite(p[2]) && distance(point, front) < 6)
            p[0] = p[1] = p[2] = static_cast<float>(kNaN);
    }
    const MeasuredPosition holed =
        fpp::calib::measure_position(ball_bar(), scan.xyz, "position-1", VerificationOptions{});
    EXPECT_LT(holed.spheres[1].coverage, whole.spheres[1].coverage - 0.02);
    EXPECT_LT(holed.spheres[1].points_used, whole.spheres[1].points_used - 50);
    EXPECT_LT(distance(holed.spheres[1].centre, c2), 0.015);
    EXPECT_NEAR(*holed.spacing_error, 0, 0.01);
}

TEST(Verification, RefusesAMissingSphere) {
    sim::Scene scene;
    scene.add(std::make_unique<sim::Sphere>(Vec3{-40, 0, 480}, kDiameter / 2, 0.85), "ball");
    scene.add(std::make_unique<sim::Cylinder>(Vec3{20, 0, 480}, Vec3{1, 0, 0}, 5, 100, 0.6), "rod");
    scene.add(std::make_unique<sim::Plane>(sim::Pose{{0, 0, 575}, {1, 0, 0, 0, 1, 0, 0, 0, 1}}, 420,
                                           330, 0.8),
              "wall");
    const fpp::InputError e = refusal(ball_bar(), scan_of(scene, 0.02));
    EXPECT_EQ(e.field(), "spheres");
    EXPECT_TRUE(says(e, "found 1 of the 2")) << e.what();
}

TEST(Verification, RefusesMoreSpheresThanTheArtefactHas) {
    sim::Scene scene = bar_scene({0, -20, 480}, {1, 0, 0}, false);
    scene.add(std::make_unique<sim::Sphere>(Vec3{0, 50, 490}, kDiameter / 2, 0.85), "other");
    const fpp::InputError e = refusal(ball_bar(), scan_of(scene, 0.02));
    EXPECT_EQ(e.field(), "spheres");
    EXPECT_TRUE(says(e, "ambiguous")) << e.what();
}

TEST(Verification, RefusesSpheresTooCloseToTellApartInView) {
    // The bar almost along the line of sight: the far sphere half hidden.
    const fpp::InputError e =
        refusal(ball_bar(), scan_of(bar_scene({0, 0, 480}, {0.15, 0, 1}, false), 0.02));
    EXPECT_EQ(e.field(), "spheres");
    EXPECT_TRUE(says(e, "too close to tell apart")) << e.what();
}

TEST(Verification, RefusesACertificateTheScansContradict) {
    const Vec3 centre{0, -10, 480}, axis{1, 0, 0.25};
    const Scan scan = scan_of(bar_scene(centre, axis, true), 0.02);
    const VerificationOptions options;
    // A length 1 mm off: a wrong certificate, not a scanner 1 mm off.
    {
        const Artefact wrong = ball_bar(kLength + 1);
        const std::vector<MeasuredPosition> positions = {
            fpp::calib::measure_position(wrong, scan.xyz, "position-1", options)};
        try {
            fpp::calib::check_certificate(wrong, positions, options);
            FAIL() << "accepted a length 1 mm off";
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.file(), std::filesystem::path("bar.yaml"));
            EXPECT_EQ(e.field(), "centre_distance_mm");
            EXPECT_TRUE(says(e, "far more than a scanner could be off")) << e.what();
        }
    }
    // A diameter 1 mm off.
    {
        const Artefact wrong = ball_bar(kLength, kDiameter + 1);
        const std::vector<MeasuredPosition> positions = {
            fpp::calib::measure_position(wrong, scan.xyz, "position-1", options)};
        try {
            fpp::calib::check_certificate(wrong, positions, options);
            FAIL() << "accepted a diameter 1 mm off";
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.field(), "sphere_diameters_mm[0]");
        }
    }
    // 0.2 mm off is a scanner that can be that far off: judged, and failed.
    {
        const Artefact off = ball_bar(kLength + 0.2);
        const std::vector<MeasuredPosition> positions = {
            fpp::calib::measure_position(off, scan.xyz, "position-1", options)};
        EXPECT_NO_THROW(fpp::calib::check_certificate(off, positions, options));
        fpp::calib::MaximumPermissibleErrors mpe;
        mpe.spacing_mm = 0.05;
        const auto figures = fpp::calib::verdicts(off, positions, mpe);
        ASSERT_EQ(figures.size(), 3u);
        EXPECT_EQ(figures[0].name, "SD");
        EXPECT_NEAR(figures[0].worst, 0.2, 0.01);
        EXPECT_FALSE(figures[0].passed());
        EXPECT_TRUE(figures[1].passed()); // P_F: no MPE, no verdict
        EXPECT_FALSE(figures[1].mpe.has_value());
    }
}

TEST(Verification, VerdictsAgainstEachMpe) {
    const Vec3 centre{0, -10, 480}, axis{1, 0, 0.25};
    const Scan scan = scan_of(bar_scene(centre, axis, true), 0.02);
    const std::vector<MeasuredPosition> positions = {
        fpp::calib::measure_position(ball_bar(), scan.xyz, "position-1", VerificationOptions{})};
    fpp::calib::MaximumPermissibleErrors mpe;
    mpe.spacing_mm = 0.02;
    mpe.form_mm = 0.3;
    mpe.size_mm = 0.02;
    for (const auto& f : fpp::calib::verdicts(ball_bar(), positions, mpe))
        EXPECT_TRUE(f.passed()) << f.name << " " << f.worst;
    mpe.form_mm = 0.01; // below the noise's range
    const auto figures = fpp::calib::verdicts(ball_bar(), positions, mpe);
    EXPECT_FALSE(figures[1].passed());
    EXPECT_EQ(figures[1].values.size(), 2u); // one per sphere
}

TEST(Verification, FindsAPlateBeforeAWall) {
    sim::Scene scene;
    scene.add(std::make_unique<sim::Plane>(sim::Pose::from_euler_deg({0, 0, 470}, 10, -15, 5), 200,
                                           150, 0.85),
              "plate");
    scene.add(std::make_unique<sim::Plane>(sim::Pose{{0, 0, 575}, {1, 0, 0, 0, 1, 0, 0, 0, 1}}, 420,
                                           330, 0.8),
              "wall");
    Artefact plate;
    plate.origin = "plate.yaml";
    plate.kind = ArtefactKind::plane;
    plate.plane_width_mm = 200;
    plate.plane_height_mm = 150;
    const MeasuredPosition m = fpp::calib::measure_position(plate, scan_of(scene, 0.02).xyz,
                                                            "position-1", VerificationOptions{});
    ASSERT_TRUE(m.plane);
    EXPECT_GT(m.plane->extent_mm[0], 190);
    EXPECT_LT(m.plane->extent_mm[0], 205);
    EXPECT_GT(m.plane->extent_mm[1], 140);
    EXPECT_LT(m.plane->extent_mm[1], 155);
    EXPECT_LT(m.plane->flatness, 0.2);
    EXPECT_LT(m.plane->rms, 0.025);

    // The wall alone is no plate of that size.
    sim::Scene wall;
    wall.add(std::make_unique<sim::Plane>(sim::Pose{{0, 0, 575}, {1, 0, 0, 0, 1, 0, 0, 0, 1}}, 420,
                                          330, 0.8),
             "wall");
    const fpp::InputError e = refusal(plate, scan_of(wall, 0.02));
    EXPECT_EQ(e.field(), "plane");
    EXPECT_TRUE(says(e, "larger")) << e.what();
}

TEST(Verification, CoverageIsTheShareOfTheHemisphereFacingTheCamera) {
    const Vec3 centre{0, 0, 500};
    std::vector<Vec3> all, half;
    for (int i = 0; i < 200; ++i)
        for (int j = 0; j < 400; ++j) {
            const double polar = (i + 0.5) / 200 * 1.5707963, azimuth = (j + 0.5) / 400 * 6.2831853;
            // Towards the camera is -Z.
            const Vec3 p{centre[0] + 15 * std::sin(polar) * std::cos(azimuth),
                         centre[1] + 15 * std::sin(polar) * std::sin(azimuth),
                         centre[2] - 15 * std::cos(polar)};
            all.push_back(p);
            if (p[0] > centre[0])
                half.push_back(p);
        }
    EXPECT_DOUBLE_EQ(fpp::calib::hemisphere_coverage(all, centre), 1.0);
    EXPECT_NEAR(fpp::calib::hemisphere_coverage(half, centre), 0.5, 0.05);
    EXPECT_DOUBLE_EQ(fpp::calib::hemisphere_coverage({}, centre), 0.0);
}

} // namespace
