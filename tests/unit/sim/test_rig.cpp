// Rig: the paper's Table 1, its geometry facts, the YAML files under
// board/sim/ (among them the rigs with lens defects) and the strictness of
// the rig reader.

#include "fpp/error.hpp"
#include "fpp/simulator/rig.hpp"
#include "lens_expect.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

namespace {

using fpp::Vec2;
using fpp::Vec3;
using fpp::sim::Rig;

Vec2 projector_pixel(const Rig& rig, const Vec3& camera_point) {
    const Vec3 r = fpp::mul(rig.R, camera_point);
    return rig.projector.project({r[0] + rig.t[0], r[1] + rig.t[1], r[2] + rig.t[2]});
}

// Fraction of the camera field (every `step` pixels, corners included) whose
// point at depth Z falls inside the projector image.
double fraction_lit_at_depth(const Rig& rig, double Z, int step) {
    long inside = 0, total = 0;
    const int W = rig.camera_size.width, H = rig.camera_size.height;
    for (int v = 0; v <= H; v += step)
        for (int u = 0; u <= W; u += step) {
            const double pu = std::min(u, W - 1), pv = std::min(v, H - 1);
            Vec2 n{};
            if (!rig.camera.pixel_to_normalised({pu, pv}, n))
                continue;
            const Vec2 p = projector_pixel(rig, {n[0] * Z, n[1] * Z, Z});
            ++total;
            if (p[0] >= -0.5 && p[0] <= rig.projector_size.width - 0.5 && p[1] >= -0.5 &&
                p[1] <= rig.projector_size.height - 0.5)
                ++inside;
        }
    return static_cast<double>(inside) / static_cast<double>(total);
}

using fpp::test::expect_same_lens;

void expect_same_geometry(const Rig& a, const Rig& b, double rotation_tolerance) {
    EXPECT_EQ(a.camera_size, b.camera_size);
    EXPECT_EQ(a.projector_size, b.projector_size);
    expect_same_lens(a.camera, b.camera);
    expect_same_lens(a.projector, b.projector);
    for (int i = 0; i < 9; ++i)
        EXPECT_NEAR(a.R[i], b.R[i], rotation_tolerance);
    for (int i = 0; i < 3; ++i)
        EXPECT_EQ(a.t[i], b.t[i]);
}

void expect_same_rig(const Rig& a, const Rig& b, double rotation_tolerance) {
    expect_same_geometry(a, b, rotation_tolerance);
    EXPECT_EQ(a.sensor.bit_depth, b.sensor.bit_depth);
    EXPECT_EQ(a.sensor.white_level, b.sensor.white_level);
    EXPECT_EQ(a.sensor.ambient, b.sensor.ambient);
    EXPECT_EQ(a.sensor.read_noise_dn, b.sensor.read_noise_dn);
    EXPECT_EQ(a.sensor.gain_e_per_dn, b.sensor.gain_e_per_dn);
    EXPECT_EQ(a.sensor.defocus_sigma_px, b.sensor.defocus_sigma_px);
    EXPECT_EQ(a.sensor.reference_distance_mm, b.sensor.reference_distance_mm);
    EXPECT_EQ(a.projector_optics.gamma, b.projector_optics.gamma);
    EXPECT_EQ(a.projector_optics.black_level, b.projector_optics.black_level);
    EXPECT_EQ(a.projector_optics.defocus_sigma_px, b.projector_optics.defocus_sigma_px);
}

TEST(SimRig, PaperRigIsTable1) {
    const Rig r = Rig::paper();
    EXPECT_EQ(r.camera_size, (fpp::Size{1600, 1200}));
    EXPECT_EQ(r.projector_size, (fpp::Size{1280, 800}));
    EXPECT_EQ(r.camera.fu, 2698.42);
    EXPECT_EQ(r.camera.fv, 2701.55);
    EXPECT_EQ(r.camera.cu, 794.59);
    EXPECT_EQ(r.camera.cv, 594.32);
    EXPECT_EQ(r.camera.skew, 0.84);
    EXPECT_EQ(r.camera.k1, -0.12);
    EXPECT_EQ(r.camera.k2, -0.52);
    EXPECT_EQ(r.camera.k3, 5.08);
    EXPECT_EQ(r.camera.p1, 0.0011);
    EXPECT_EQ(r.camera.p2, 0.0006);
    EXPECT_EQ(r.projector.fu, 1949.18);
    EXPECT_EQ(r.projector.fv, 1953.15);
    EXPECT_EQ(r.projector.cu, 632.42);
    EXPECT_EQ(r.projector.cv, 799.67);
    EXPECT_EQ(r.projector.skew, 0.83);
    EXPECT_EQ(r.projector.k1, 0.002);
    EXPECT_EQ(r.projector.k2, -0.077);
    EXPECT_EQ(r.projector.k3, -0.033);
    EXPECT_EQ(r.projector.p1, 0.0004);
    EXPECT_EQ(r.projector.p2, 0.0002);
    const fpp::Mat3 R = fpp::rotation_from_euler_deg(-0.42, 19.08, 0.36);
    for (int i = 0; i < 9; ++i)
        EXPECT_EQ(r.R[i], R[i]);
    EXPECT_EQ(r.t, (Vec3{-163.71, -116.73, 135.41}));
    // Effects off: ideal 8-bit, noise-free.
    EXPECT_EQ(r.sensor.bit_depth, 8);
    EXPECT_EQ(r.sensor.read_noise_dn, 0);
    EXPECT_EQ(r.sensor.gain_e_per_dn, 0);
    EXPECT_EQ(r.projector_optics.gamma, 1);
    EXPECT_FALSE(r.camera.has_unmodelled_terms());
    EXPECT_FALSE(r.projector.has_unmodelled_terms());
}

TEST(SimRig, ProjectorCentreSitsRightOfAndBelowTheCamera) {
    // -R^T t with R = Rz Ry Rx: about (200, 116, -73) mm in the camera frame.
    const Vec3 c = Rig::paper().projector_centre_in_camera();
    EXPECT_NEAR(c[0], 199.67, 0.01);
    EXPECT_NEAR(c[1], 116.24, 0.01);
    EXPECT_NEAR(c[2], -73.37, 0.01);
    // And it is the point that the projector frame puts at its origin.
    const Vec3 p = fpp::mul(Rig::paper().R, c);
    const Vec3 t = Rig::paper().t;
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(p[i] + t[i], 0, 1e-12);
}

TEST(SimRig, ProjectorLightsTheCameraFieldOverTheCalibrationVolume) {
    const Rig rig = Rig::paper();
    // The whole camera field is inside the projector image from 450 to 490 mm
    // (the plane scenes sit at 480 mm) ...
    for (double Z = 450; Z <= 490; Z += 5)
        EXPECT_EQ(fraction_lit_at_depth(rig, Z, 10), 1.0) << Z;
    // ... but not over the whole 400-560 mm volume: at the far end the bottom
    // rows of the camera fall below the projector image, at the near end a
    // sliver of the top corner above it.
    EXPECT_LT(fraction_lit_at_depth(rig, 440, 10), 1.0);
    EXPECT_LT(fraction_lit_at_depth(rig, 500, 10), 1.0);
    for (double Z = 400; Z <= 560; Z += 20)
        EXPECT_GT(fraction_lit_at_depth(rig, Z, 10), 0.93) << Z;
    EXPECT_LT(fraction_lit_at_depth(rig, 560, 10), 0.94);
    // The field's lateral extent at 480 mm matches the paper's volume (about 270 x 200 mm).
    Vec2 a{}, b{};
    ASSERT_TRUE(rig.camera.pixel_to_normalised({-0.5, 599.5}, a));
    ASSERT_TRUE(rig.camera.pixel_to_normalised({1599.5, 599.5}, b));
    EXPECT_NEAR((b[0] - a[0]) * 480, 285, 5);
}

TEST(SimRig, PaperRigYamlIsTheBuiltInRig) {
    const Rig from_file = fpp::sim::load_rig(fpp::sim::default_rig_path());
    EXPECT_EQ(from_file.name, "paper-rig");
    expect_same_rig(from_file, Rig::paper(), 0.0);
    EXPECT_EQ(from_file.sensor.white_level, 240);
}

TEST(SimRig, EffectsRigHasTheDocumentedEffects) {
    const Rig e = fpp::sim::load_rig(fpp::sim::effects_rig_path());
    const Rig base = e.without_effects();
    // Same geometry as the paper's.
    expect_same_geometry(base, Rig::paper(), 0.0);
    EXPECT_EQ(e.projector_optics.gamma, 2.2);
    EXPECT_NEAR(e.projector_optics.defocus_sigma_px, 0.8, 1e-12);
    EXPECT_NEAR(e.sensor.defocus_sigma_px, 0.5, 1e-12);
    EXPECT_EQ(e.sensor.read_noise_dn, 1.0);
    EXPECT_GT(e.sensor.gain_e_per_dn, 0);
    EXPECT_GT(e.sensor.ambient, 0);
    EXPECT_EQ(e.sensor.bit_depth, 8);
    // The unmodelled projector distortion moves the image by a few tenths of a
    // projector pixel at the field edge and by nothing at the principal point.
    auto shift = [&](double u, double v) {
        Vec2 n{};
        EXPECT_TRUE(base.projector.pixel_to_normalised({u, v}, n));
        const Vec2 p = e.projector.project({n[0], n[1], 1});
        return std::hypot(p[0] - u, p[1] - v);
    };
    EXPECT_LT(shift(632.42, 799.67), 1e-9);
    const double corner = std::max(shift(0, 0), shift(1279, 0));
    EXPECT_GT(corner, 0.2);
    EXPECT_LT(corner, 0.7);
    EXPECT_GT(shift(640, 0), 0.05);
}

// The paper's lenses within the 5-coefficient model, the effects of
// paper-rig-effects.yaml (radiometry, defocus, noise), and the camera field
// lit over the calibration volume (almost all of it at the plane scene's 480 mm).
void expect_paper_family_with_effects(const Rig& r) {
    const Rig paper = Rig::paper();
    EXPECT_EQ(r.camera_size, paper.camera_size);
    EXPECT_EQ(r.projector_size, paper.projector_size);
    expect_same_lens(r.without_effects().camera, paper.camera);
    expect_same_lens(r.without_effects().projector, paper.projector);
    // r with the effects rig's sensor and projector optics is r itself.
    const Rig e = fpp::sim::load_rig(fpp::sim::effects_rig_path());
    Rig with_those_effects = r;
    with_those_effects.sensor = e.sensor;
    with_those_effects.projector_optics = e.projector_optics;
    expect_same_rig(r, with_those_effects, 0.0);
    EXPECT_GT(fraction_lit_at_depth(r, 480, 10), 0.99) << r.name;
    for (double Z = 400; Z <= 560; Z += 20)
        EXPECT_GT(fraction_lit_at_depth(r, Z, 10), 0.9) << r.name << " " << Z;
}

// Largest displacement (pixels) of the device's image that its unmodelled
// terms cause, over the image's border and centre lines.
double largest_unmodelled_shift(const fpp::LensModel& lens, fpp::Size size) {
    fpp::LensModel modelled = lens;
    modelled.drop_unmodelled_terms();
    double largest = 0;
    for (int i = 0; i <= 32; ++i)
        for (int j = 0; j <= 32; j += 16) {
            for (const Vec2 px :
                 {Vec2{(size.width - 1) * i / 32.0, (size.height - 1) * j / 32.0},
                  Vec2{(size.width - 1) * j / 32.0, (size.height - 1) * i / 32.0}}) {
                Vec2 n{};
                EXPECT_TRUE(modelled.pixel_to_normalised(px, n));
                const Vec2 p = lens.project({n[0], n[1], 1});
                largest = std::max(largest, std::hypot(p[0] - px[0], p[1] - px[1]));
            }
        }
    return largest;
}

TEST(SimRig, PrismProjectorRigIsAsDocumented) {
    const Rig r = fpp::sim::load_rig(fpp::sim::prism_projector_rig_path());
    EXPECT_EQ(r.name, "rig-prism-projector");
    expect_paper_family_with_effects(r);
    EXPECT_FALSE(r.camera.has_unmodelled_terms());
    EXPECT_EQ(r.projector.s1, 0.0006);
    EXPECT_EQ(r.projector.s2, 0.033);
    EXPECT_EQ(r.projector.s3, -0.0005);
    EXPECT_EQ(r.projector.s4, -0.029);
    EXPECT_EQ(r.projector.k4, 0);
    EXPECT_EQ(r.projector.t1, 0);
    EXPECT_EQ(r.projector.dc_k2, 0);
    // Up to ~7 projector pixels at the corners.
    const double shift = largest_unmodelled_shift(r.projector, r.projector_size);
    EXPECT_GT(shift, 5);
    EXPECT_LT(shift, 9);
    // Left of the camera (the paper rig's projector is right of it), ~150 mm away.
    const Vec3 c = r.projector_centre_in_camera();
    EXPECT_NEAR(c[0], -115, 0.1);
    EXPECT_NEAR(c[1], 40, 0.1);
    EXPECT_NEAR(c[2], -90, 0.1);
    EXPECT_NEAR(std::hypot(c[0], c[1], c[2]), 151.4, 0.1);
}

TEST(SimRig, CameraDefectRigIsAsDocumented) {
    const Rig r = fpp::sim::load_rig(fpp::sim::camera_defect_rig_path());
    EXPECT_EQ(r.name, "rig-camera-defect");
    expect_paper_family_with_effects(r);
    // The defect is on the camera; the projector has only modelled distortion.
    EXPECT_FALSE(r.projector.has_unmodelled_terms());
    EXPECT_EQ(r.camera.k4, 1.0);
    EXPECT_EQ(r.camera.t1, 0.0035);
    EXPECT_EQ(r.camera.t2, -0.0025);
    const double shift = largest_unmodelled_shift(r.camera, r.camera_size);
    EXPECT_GT(shift, 1.5);
    EXPECT_LT(shift, 2.5);
    // Right of and a little above the camera, ~300 mm away.
    const Vec3 c = r.projector_centre_in_camera();
    EXPECT_NEAR(c[0], 290, 0.1);
    EXPECT_NEAR(c[1], -30, 0.1);
    EXPECT_NEAR(c[2], -50, 0.1);
}

TEST(SimRig, DecentredProjectorRigIsAsDocumented) {
    const Rig r = fpp::sim::load_rig(fpp::sim::decentred_projector_rig_path());
    EXPECT_EQ(r.name, "rig-decentred-projector");
    expect_paper_family_with_effects(r);
    EXPECT_FALSE(r.camera.has_unmodelled_terms());
    EXPECT_EQ(r.projector.dc_k1, 0.02);
    EXPECT_EQ(r.projector.dc_k2, 0.15);
    EXPECT_EQ(r.projector.dc_x, 0.05);
    EXPECT_EQ(r.projector.dc_y, -0.45);
    EXPECT_EQ(r.projector.k4, 0);
    EXPECT_EQ(r.projector.s1, 0);
    EXPECT_EQ(r.projector.t1, 0);
    // The principal point stays put.
    Vec2 n{};
    ASSERT_TRUE(r.projector.pixel_to_normalised({r.projector.cu, r.projector.cv}, n));
    EXPECT_LT(std::hypot(n[0], n[1]), 1e-12);
    // Above the camera, with a horizontal baseline of 130 mm for the columns to
    // triangulate with.
    const Vec3 c = r.projector_centre_in_camera();
    EXPECT_NEAR(c[0], 130, 0.1);
    EXPECT_NEAR(c[1], -170, 0.1);
    EXPECT_NEAR(c[2], -60, 0.1);
    // Upside down, its columns still vertical in the camera frame: the
    // projector's x axis is nearly horizontal (pointing to -x).
    const fpp::Mat3 Rt = fpp::transpose(r.R);
    EXPECT_LT(Rt[0], -0.95);
    EXPECT_LT(std::fabs(Rt[3]), 0.05);
    // Depth comes from the column: along a camera ray the column moves by many
    // pixels over the volume (the plane scene's centre ray, 400 to 560 mm).
    const Vec2 near = projector_pixel(r, {0, 0, 400}), far = projector_pixel(r, {0, 0, 560});
    EXPECT_GT(std::fabs(far[0] - near[0]), 100);
}

TEST(SimRig, YamlRoundTripWithARotationMatrix) {
    fpp::test::TempDir dir;
    Rig r = fpp::sim::load_rig(fpp::sim::effects_rig_path());
    r.name = "round \"trip\"";
    r.sensor.bit_depth = 12;
    r.camera.t1 = 2.5e-4;
    r.projector.t2 = -7.5e-4;
    const auto path = dir / "rig.yaml";
    std::ofstream(path) << fpp::sim::rig_to_yaml(r);
    const Rig back = fpp::sim::load_rig(path);
    EXPECT_EQ(back.name, r.name);
    expect_same_rig(back, r, 0.0);
}

TEST(SimRig, YamlRoundTripWithEveryUnmodelledTermOnBothLenses) {
    fpp::test::TempDir dir;
    Rig r = fpp::sim::load_rig(fpp::sim::decentred_projector_rig_path());
    r.camera.k4 = 0.5;
    r.camera.s2 = 1e-3;
    r.camera.t1 = 2.5e-4;
    r.camera.dc_k1 = 0.01;
    r.camera.dc_k2 = -0.125;
    r.camera.dc_x = -0.0625;
    r.camera.dc_y = 0.1;
    r.projector.s4 = -3e-3;
    r.projector.dc_x = 1.0 / 3.0; // not a short decimal: written to round-trip exactly
    const auto path = dir / "rig.yaml";
    std::ofstream(path) << fpp::sim::rig_to_yaml(r);
    expect_same_rig(fpp::sim::load_rig(path), r, 0.0);
    // An element's centre without coefficients distorts nothing but is still written.
    Rig centre_only = Rig::paper();
    centre_only.camera.dc_x = 0.25;
    centre_only.camera.dc_y = -0.5;
    std::ofstream(path) << fpp::sim::rig_to_yaml(centre_only);
    expect_same_rig(fpp::sim::load_rig(path), centre_only, 0.0);
}

TEST(SimRig, BinnedCameraKeepsTheRays) {
    const Rig r = Rig::paper();
    const Rig b = r.binned_camera(4);
    EXPECT_EQ(b.camera_size, (fpp::Size{400, 300}));
    const Vec3 p{31.5, -22.25, 470};
    const Vec2 full = r.camera.project(p), binned = b.camera.project(p);
    EXPECT_NEAR(binned[0], (full[0] + 0.5) / 4 - 0.5, 1e-9);
    EXPECT_NEAR(binned[1], (full[1] + 0.5) / 4 - 0.5, 1e-9);
}

// ---- rejections -----------------------------------------------------------

std::string paper_yaml() {
    std::ifstream in(fpp::sim::default_rig_path());
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

// Replaces the first occurrence of `from` in the body (after the schema comment).
std::string replaced(std::string text, const std::string& from, const std::string& to) {
    const auto body = text.find("\nformat:");
    EXPECT_NE(body, std::string::npos);
    const auto pos = text.find(from, body);
    EXPECT_NE(pos, std::string::npos) << from;
    if (pos != std::string::npos)
        text.replace(pos, from.size(), to);
    return text;
}

// Loads `yaml` from a file and expects an InputError naming that file and `field`.
void expect_rejected(const std::string& yaml, const std::string& field) {
    fpp::test::TempDir dir;
    const auto path = dir / "bad-rig.yaml";
    std::ofstream(path) << yaml;
    try {
        fpp::sim::load_rig(path);
        ADD_FAILURE() << "accepted a rig with a bad " << field;
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_EQ(e.field(), field) << e.what();
        EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
}

TEST(SimRigYaml, UnmodelledDistortionKeysAreCheckedOnBothLenses) {
    const std::string camera_line = "  distortion: {k1: -0.12, k2: -0.52, k3: 5.08, p1: 0.0011, "
                                    "p2: 0.0006}\n";
    const std::string projector_line = "  distortion: {k1: 0.002, k2: -0.077, k3: -0.033, p1: "
                                       "0.0004, p2: 0.0002}\n";
    auto with_camera = [&](const std::string& map) {
        return replaced(paper_yaml(), camera_line,
                        camera_line + "  unmodelled_distortion: " + map + "\n");
    };
    auto with_projector = [&](const std::string& map) {
        return replaced(paper_yaml(), projector_line,
                        projector_line + "  unmodelled_distortion: " + map + "\n");
    };
    // Every key is accepted on either lens.
    fpp::test::TempDir dir;
    const std::string all = "{k4: 0.1, s1: 1e-4, s2: 2e-4, s3: 3e-4, s4: 4e-4, t1: 5e-4, t2: "
                            "6e-4, dc_k1: 0.01, dc_k2: 0.02, dc_x: 0.03, dc_y: -0.04}";
    for (const std::string& yaml : {with_camera(all), with_projector(all)}) {
        std::ofstream(dir / "rig.yaml") << yaml;
        const Rig r = fpp::sim::load_rig(dir / "rig.yaml");
        const fpp::LensModel& l = r.camera.has_unmodelled_terms() ? r.camera : r.projector;
        EXPECT_EQ(l.t2, 6e-4);
        EXPECT_EQ(l.dc_k1, 0.01);
        EXPECT_EQ(l.dc_k2, 0.02);
        EXPECT_EQ(l.dc_x, 0.03);
        EXPECT_EQ(l.dc_y, -0.04);
    }
    expect_rejected(with_camera("{dc_k2: .nan}"), "camera.unmodelled_distortion.dc_k2");
    expect_rejected(with_projector("{dc_k1: 0.01, dc_x: .inf}"),
                    "projector.unmodelled_distortion.dc_x");
    expect_rejected(with_projector("{t1: nan}"), "projector.unmodelled_distortion.t1");
    expect_rejected(with_camera("{dc_y: abc}"), "camera.unmodelled_distortion.dc_y");
    expect_rejected(with_camera("{dc_k3: 0.1}"), "camera.unmodelled_distortion.dc_k3");
    expect_rejected(with_projector("{k1: 0.1}"), "projector.unmodelled_distortion.k1");
}

TEST(SimRigYaml, RejectsUnknownKeys) {
    expect_rejected(paper_yaml() + "colour: blue\n", "colour");
    expect_rejected(replaced(paper_yaml(), "  skew: 0.84\n", "  skew: 0.84\n  skwe: 1\n"),
                    "camera.skwe");
    expect_rejected(replaced(paper_yaml(), "p2: 0.0006}", "p2: 0.0006, k4: 0.1}"),
                    "camera.distortion.k4");
    expect_rejected(
        replaced(paper_yaml(), "  white_level: 240\n", "  white_level: 240\n  iso: 100\n"),
        "sensor.iso");
}

TEST(SimRigYaml, RejectsMissingFields) {
    expect_rejected(replaced(paper_yaml(), "  focal_px: [2698.42, 2701.55]\n", ""),
                    "camera.focal_px");
    expect_rejected(replaced(paper_yaml(), "  white_level: 240\n", ""), "sensor.white_level");
    expect_rejected(replaced(paper_yaml(), "k3: -0.033, ", ""), "projector.distortion.k3");
    expect_rejected(replaced(paper_yaml(), "  translation_mm: [-163.71, -116.73, 135.41]\n", ""),
                    "extrinsics.translation_mm");
    expect_rejected(replaced(paper_yaml(), "format: fpp-rig/1\n", ""), "format");
}

TEST(SimRigYaml, RejectsNonFiniteNumbers) {
    expect_rejected(replaced(paper_yaml(), "skew: 0.84", "skew: .nan"), "camera.skew");
    expect_rejected(replaced(paper_yaml(), "k1: 0.002", "k1: nan"), "projector.distortion.k1");
    expect_rejected(replaced(paper_yaml(), "[-163.71, -116.73, 135.41]", "[-163.71, .inf, 135.41]"),
                    "extrinsics.translation_mm[1]");
    expect_rejected(replaced(paper_yaml(), "[-0.42, 19.08, 0.36]", "[-0.42, 19.08, -inf]"),
                    "extrinsics.euler_deg[2]");
}

TEST(SimRigYaml, RejectsBadValues) {
    expect_rejected(replaced(paper_yaml(), "format: fpp-rig/1", "format: fpp-rig/2"), "format");
    expect_rejected(replaced(paper_yaml(), "bit_depth: 8", "bit_depth: 9"), "sensor.bit_depth");
    expect_rejected(replaced(paper_yaml(), "bit_depth: 8", "bit_depth: 8.5"), "sensor.bit_depth");
    expect_rejected(replaced(paper_yaml(), "focal_px: [2698.42, 2701.55]", "focal_px: [2698.42]"),
                    "camera.focal_px");
    expect_rejected(
        replaced(paper_yaml(), "focal_px: [1949.18, 1953.15]", "focal_px: [-1949.18, 1953.15]"),
        "projector.focal_px");
    expect_rejected(replaced(paper_yaml(), "skew: 0.84", "skew: abc"), "camera.skew");
    expect_rejected(
        replaced(paper_yaml(), "  white_level: 240\n", "  white_level: 240\n  read_noise_dn: -1\n"),
        "sensor.read_noise_dn");
    expect_rejected(paper_yaml() + "projector_optics: {gamma: 0}\n", "projector_optics.gamma");
    // Both rotation forms, or a matrix that is not a rotation.
    expect_rejected(
        replaced(
            paper_yaml(), "  euler_deg: [-0.42, 19.08, 0.36]\n",
            "  euler_deg: [-0.42, 19.08, 0.36]\n  rotation: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n"),
        "extrinsics");
    expect_rejected(replaced(paper_yaml(), "  euler_deg: [-0.42, 19.08, 0.36]\n",
                             "  rotation: [[1, 0, 0], [0, 1, 0], [0, 0, 1.1]]\n"),
                    "extrinsics.rotation");
    expect_rejected(replaced(paper_yaml(), "  euler_deg: [-0.42, 19.08, 0.36]\n",
                             "  rotation: [[1, 0, 0], [0, 1, 0], [0, 0, -1]]\n"),
                    "extrinsics.rotation");
    expect_rejected(replaced(paper_yaml(), "  euler_deg: [-0.42, 19.08, 0.36]\n",
                             "  rotation: [[1, 0, 0], [0, 1, 0]]\n"),
                    "extrinsics.rotation");
}

TEST(SimRigYaml, RejectsUnreadableFiles) {
    fpp::test::TempDir dir;
    EXPECT_THROW(fpp::sim::load_rig(dir / "missing.yaml"), fpp::InputError);
    expect_rejected("format: [unclosed\n", "");
    expect_rejected("- a list\n- not a map\n", "(top level)");
    expect_rejected(paper_yaml() + "name: twice\n", "name");
}

TEST(SimRigYaml, AcceptsARotationMatrix) {
    const std::string yaml = replaced(paper_yaml(), "  euler_deg: [-0.42, 19.08, 0.36]\n",
                                      "  rotation: [[0, -1, 0], [1, 0, 0], [0, 0, 1]]\n");
    fpp::test::TempDir dir;
    const auto path = dir / "rot.yaml";
    std::ofstream(path) << yaml;
    const Rig r = fpp::sim::load_rig(path);
    const fpp::Mat3 expected = fpp::rotation_from_euler_deg(0, 0, 90);
    for (int i = 0; i < 9; ++i)
        EXPECT_NEAR(r.R[i], expected[i], 1e-15);
    EXPECT_EQ(r.name, "paper-rig");
}

} // namespace
