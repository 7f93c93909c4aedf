// Lens model: distortion, its Jacobian, Newton undistortion over the whole
// image for the paper's camera (strong k3 = 5.08) and projector and for the
// lenses of the rigs with defects, the decentred element, skew and the
// Euler-angle convention.

#include "fpp/lens_model.hpp"
#include "fpp/simulator/rig.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace {

using fpp::LensModel;
using fpp::Mat3;
using fpp::Vec2;
using fpp::Vec3;

double dist2(const Vec2& a, const Vec2& b) {
    return std::hypot(a[0] - b[0], a[1] - b[1]);
}

struct RoundTrip {
    double max_normalised = 0; // |n' - n| after project then unproject
    double max_pixel = 0;      // |pixel' - pixel| after unproject then project
    int failures = 0;
    int samples = 0;
};

// Every `step` pixels over the image, plus its outer border (pixel edges at -0.5 and size - 0.5).
RoundTrip round_trip_over_image(const LensModel& lens, fpp::Size size, double step) {
    RoundTrip r;
    auto visit = [&](double u, double v) {
        ++r.samples;
        Vec2 n{};
        if (!lens.pixel_to_normalised({u, v}, n)) {
            ++r.failures;
            return;
        }
        const Vec2 pixel = lens.project({n[0], n[1], 1.0});
        r.max_pixel = std::max(r.max_pixel, dist2(pixel, {u, v}));
        Vec2 n2{};
        if (!lens.pixel_to_normalised(pixel, n2)) {
            ++r.failures;
            return;
        }
        r.max_normalised = std::max(r.max_normalised, dist2(n, n2));
    };
    for (double v = -0.5; v <= size.height - 0.5; v += step)
        for (double u = -0.5; u <= size.width - 0.5; u += step)
            visit(u, v);
    for (double u = -0.5; u <= size.width - 0.5; u += 1) {
        visit(u, -0.5);
        visit(u, size.height - 0.5);
    }
    for (double v = -0.5; v <= size.height - 0.5; v += 1) {
        visit(-0.5, v);
        visit(size.width - 0.5, v);
    }
    return r;
}

LensModel lens_with_every_term() {
    LensModel l = fpp::sim::Rig::paper().projector;
    l.k4 = 0.04;
    l.s1 = 3e-4;
    l.s2 = -2e-4;
    l.s3 = -2.5e-4;
    l.s4 = 1e-4;
    l.t1 = 1e-3;
    l.t2 = 5e-4;
    l.dc_k1 = 0.02;
    l.dc_k2 = 0.15;
    l.dc_x = 0.05;
    l.dc_y = -0.45;
    return l;
}

LensModel decentred_only() {
    LensModel l;
    l.dc_k1 = 0.03;
    l.dc_k2 = -0.2;
    l.dc_x = 0.12;
    l.dc_y = -0.3;
    return l;
}

TEST(LensModel, DistortMatchesTheFormula) {
    LensModel l;
    l.k1 = 0.1;
    l.k2 = -0.2;
    l.k3 = 0.3;
    l.p1 = 0.01;
    l.p2 = -0.02;
    l.k4 = 0.05;
    l.s1 = 0.003;
    l.s2 = -0.004;
    l.s3 = 0.005;
    l.s4 = -0.006;
    l.t1 = 0.007;
    l.t2 = -0.008;
    const double x = 0.3, y = -0.2, r2 = x * x + y * y;
    const double radial =
        1 + 0.1 * r2 - 0.2 * r2 * r2 + 0.3 * r2 * r2 * r2 + 0.05 * r2 * r2 * r2 * r2;
    // Trefoil: Re and Im of (0.007 - 0.008 i) (x - i y)^2.
    const double trefoil_x = 0.007 * (x * x - y * y) - 0.008 * 2 * x * y;
    const double trefoil_y = -0.008 * (x * x - y * y) - 0.007 * 2 * x * y;
    const double xd = x * radial + 2 * 0.01 * x * y - 0.02 * (r2 + 2 * x * x) + 0.003 * r2 -
                      0.004 * r2 * r2 + trefoil_x;
    const double yd = y * radial + 0.01 * (r2 + 2 * y * y) + 2 * -0.02 * x * y + 0.005 * r2 -
                      0.006 * r2 * r2 + trefoil_y;
    const Vec2 d = l.distort({x, y});
    EXPECT_NEAR(d[0], xd, 1e-15);
    EXPECT_NEAR(d[1], yd, 1e-15);
}

TEST(LensModel, JacobianMatchesFiniteDifferences) {
    const LensModel l = lens_with_every_term();
    const LensModel cam = fpp::sim::Rig::paper().camera;
    for (const LensModel* lens : {&l, &cam}) {
        for (const Vec2 n :
             {Vec2{0.0, 0.0}, Vec2{0.3, -0.2}, Vec2{-0.31, -0.41}, Vec2{0.12, 0.25}}) {
            const fpp::Mat2 J = lens->distortion_jacobian(n);
            const double h = 1e-6;
            const Vec2 xp = lens->distort({n[0] + h, n[1]}), xm = lens->distort({n[0] - h, n[1]});
            const Vec2 yp = lens->distort({n[0], n[1] + h}), ym = lens->distort({n[0], n[1] - h});
            EXPECT_NEAR(J[0], (xp[0] - xm[0]) / (2 * h), 1e-8);
            EXPECT_NEAR(J[1], (yp[0] - ym[0]) / (2 * h), 1e-8);
            EXPECT_NEAR(J[2], (xp[1] - xm[1]) / (2 * h), 1e-8);
            EXPECT_NEAR(J[3], (yp[1] - ym[1]) / (2 * h), 1e-8);
        }
    }
}

TEST(LensModel, DecentredElementMatchesTheFormula) {
    const LensModel l = decentred_only();
    const double x = 0.3, y = -0.2;
    // Radial distortion about (0.12, -0.3), minus its value on the axis.
    const double dx = x - 0.12, dy = y + 0.3, rho2 = dx * dx + dy * dy;
    const double g = 0.03 * rho2 - 0.2 * rho2 * rho2;
    const double rho2_axis = 0.12 * 0.12 + 0.3 * 0.3;
    const double g_axis = 0.03 * rho2_axis - 0.2 * rho2_axis * rho2_axis;
    const Vec2 d = l.distort({x, y});
    EXPECT_NEAR(d[0], x + dx * g - (-0.12) * g_axis, 1e-15);
    EXPECT_NEAR(d[1], y + dy * g - 0.3 * g_axis, 1e-15);
    // The axis stays where it is (to rounding: with fused multiply-adds, as on
    // AArch64, the two cancelling products leave ~1e-20); the element's centre
    // moves by the axis offset only.
    const Vec2 axis = l.distort({0, 0});
    EXPECT_NEAR(axis[0], 0, 1e-16);
    EXPECT_NEAR(axis[1], 0, 1e-16);
    const Vec2 centre = l.distort({0.12, -0.3});
    EXPECT_NEAR(centre[0], 0.12 + 0.12 * g_axis, 1e-15);
    EXPECT_NEAR(centre[1], -0.3 - 0.3 * g_axis, 1e-15);
    // Without dc_k1 and dc_k2 the centre alone changes nothing.
    LensModel centre_only;
    centre_only.dc_x = 0.2;
    centre_only.dc_y = -0.1;
    const Vec2 same = centre_only.distort({x, y});
    EXPECT_EQ(same[0], x);
    EXPECT_EQ(same[1], y);
}

// The header's claim: with dc_k2 = 0 the element is exactly k1 = dc_k1,
// p1 = -dc_k1 dc_y, p2 = -dc_k1 dc_x plus dc_k1 (|e|^2 I + 2 e e^T) applied
// to (x, y), e = (dc_x, dc_y): a linear map that the pinhole and the pose take.
TEST(LensModel, DecentredSecondOrderPartIsRadialTangentialAndLinear) {
    LensModel decentred;
    decentred.dc_k1 = 0.05;
    decentred.dc_x = 0.1;
    decentred.dc_y = -0.25;
    LensModel modelled;
    modelled.k1 = 0.05;
    modelled.p1 = -0.05 * -0.25;
    modelled.p2 = -0.05 * 0.1;
    const double ex = 0.1, ey = -0.25, e2 = ex * ex + ey * ey;
    for (const Vec2 n : {Vec2{0.3, -0.2}, Vec2{-0.31, -0.41}, Vec2{0.12, 0.25}}) {
        const Vec2 a = decentred.distort(n), b = modelled.distort(n);
        const double lx = 0.05 * ((e2 + 2 * ex * ex) * n[0] + 2 * ex * ey * n[1]);
        const double ly = 0.05 * (2 * ex * ey * n[0] + (e2 + 2 * ey * ey) * n[1]);
        EXPECT_NEAR(a[0], b[0] + lx, 1e-15);
        EXPECT_NEAR(a[1], b[1] + ly, 1e-15);
    }
}

TEST(LensModel, DecentredJacobianMatchesCentralDifferences) {
    const LensModel l = decentred_only();
    // Including the element's centre (rho = 0) and points far from it.
    for (const Vec2 n : {Vec2{0.0, 0.0}, Vec2{0.12, -0.3}, Vec2{0.3, -0.2}, Vec2{-0.33, -0.41},
                         Vec2{0.33, 0.0}, Vec2{-0.2, 0.15}}) {
        const fpp::Mat2 J = l.distortion_jacobian(n);
        const double h = 1e-6;
        const Vec2 xp = l.distort({n[0] + h, n[1]}), xm = l.distort({n[0] - h, n[1]});
        const Vec2 yp = l.distort({n[0], n[1] + h}), ym = l.distort({n[0], n[1] - h});
        EXPECT_NEAR(J[0], (xp[0] - xm[0]) / (2 * h), 1e-9) << n[0] << " " << n[1];
        EXPECT_NEAR(J[1], (yp[0] - ym[0]) / (2 * h), 1e-9) << n[0] << " " << n[1];
        EXPECT_NEAR(J[2], (xp[1] - xm[1]) / (2 * h), 1e-9) << n[0] << " " << n[1];
        EXPECT_NEAR(J[3], (yp[1] - ym[1]) / (2 * h), 1e-9) << n[0] << " " << n[1];
    }
}

TEST(LensModel, UnmodelledTermsAreReportedAndDropped) {
    EXPECT_FALSE(fpp::sim::Rig::paper().projector.has_unmodelled_terms());
    auto with = [](auto set) {
        LensModel l = fpp::sim::Rig::paper().projector;
        set(l);
        return l;
    };
    const LensModel lenses[] = {with([](LensModel& l) { l.k4 = 0.01; }),
                                with([](LensModel& l) { l.s2 = 1e-4; }),
                                with([](LensModel& l) { l.t1 = 1e-4; }),
                                with([](LensModel& l) { l.t2 = -1e-4; }),
                                with([](LensModel& l) { l.dc_k1 = 0.01; }),
                                with([](LensModel& l) { l.dc_k2 = -0.01; }),
                                lens_with_every_term()};
    for (LensModel l : lenses) {
        EXPECT_TRUE(l.has_unmodelled_terms());
        l.drop_unmodelled_terms();
        EXPECT_FALSE(l.has_unmodelled_terms());
        EXPECT_EQ(l.dc_x, 0);
        EXPECT_EQ(l.dc_y, 0);
        // What is left is the 5-coefficient lens.
        const Vec2 a = l.distort({0.2, -0.3});
        const Vec2 b = fpp::sim::Rig::paper().projector.distort({0.2, -0.3});
        EXPECT_EQ(a[0], b[0]);
        EXPECT_EQ(a[1], b[1]);
    }
    // The element's centre alone is no term: it distorts nothing.
    LensModel centre_only;
    centre_only.dc_x = 0.1;
    centre_only.dc_y = -0.2;
    EXPECT_FALSE(centre_only.has_unmodelled_terms());
}

TEST(LensModel, SkewEntersAsInTheHeader) {
    LensModel l;
    l.fu = 2000;
    l.fv = 2100;
    l.cu = 800;
    l.cv = 600;
    l.skew = 5;
    const Vec2 p = l.distorted_to_pixel({0.1, -0.2});
    EXPECT_DOUBLE_EQ(p[0], 2000 * 0.1 + 5 * -0.2 + 800);
    EXPECT_DOUBLE_EQ(p[1], 2100 * -0.2 + 600);
    const Vec2 d = l.pixel_to_distorted(p);
    EXPECT_NEAR(d[0], 0.1, 1e-15);
    EXPECT_NEAR(d[1], -0.2, 1e-15);
    // No distortion: projecting a point is the pinhole with skew.
    const Vec2 q = l.project({30, -40, 500});
    EXPECT_NEAR(q[0], 2000 * 0.06 + 5 * -0.08 + 800, 1e-12);
    EXPECT_NEAR(q[1], 2100 * -0.08 + 600, 1e-12);
}

TEST(LensModel, PaperCameraRoundTripOverTheWholeImage) {
    const fpp::sim::Rig rig = fpp::sim::Rig::paper();
    const RoundTrip r = round_trip_over_image(rig.camera, rig.camera_size, 4.0);
    EXPECT_EQ(r.failures, 0);
    EXPECT_LT(r.max_normalised, 1e-9);
    EXPECT_LT(r.max_pixel, 1e-9);
    RecordProperty("camera_max_normalised_error", std::to_string(r.max_normalised));
    RecordProperty("camera_max_pixel_error", std::to_string(r.max_pixel));
    std::printf("paper camera, %d samples: max round trip %.3g normalised, %.3g px\n", r.samples,
                r.max_normalised, r.max_pixel);
}

TEST(LensModel, PaperProjectorRoundTripOverTheWholeImage) {
    const fpp::sim::Rig rig = fpp::sim::Rig::paper();
    const RoundTrip r = round_trip_over_image(rig.projector, rig.projector_size, 4.0);
    EXPECT_EQ(r.failures, 0);
    EXPECT_LT(r.max_normalised, 1e-9);
    EXPECT_LT(r.max_pixel, 1e-9);
    std::printf("paper projector, %d samples: max round trip %.3g normalised, %.3g px\n", r.samples,
                r.max_normalised, r.max_pixel);
}

TEST(LensModel, RoundTripWithTermsOutsideTheCalibratedModel) {
    const fpp::sim::Rig rig = fpp::sim::Rig::paper();
    const RoundTrip r = round_trip_over_image(lens_with_every_term(), rig.projector_size, 8.0);
    EXPECT_EQ(r.failures, 0);
    EXPECT_LT(r.max_normalised, 1e-9);
}

// The camera and projector lenses of every rig with a lens defect, at full size.
TEST(LensModel, DefectRigLensesRoundTripOverTheWholeImage) {
    for (const auto& path :
         {fpp::sim::lens_defects_rig_path(), fpp::sim::prism_projector_rig_path(),
          fpp::sim::camera_defect_rig_path(), fpp::sim::decentred_projector_rig_path()}) {
        const fpp::sim::Rig rig = fpp::sim::load_rig(path);
        const RoundTrip camera = round_trip_over_image(rig.camera, rig.camera_size, 8.0);
        const RoundTrip projector = round_trip_over_image(rig.projector, rig.projector_size, 8.0);
        EXPECT_EQ(camera.failures, 0) << path;
        EXPECT_LT(camera.max_normalised, 1e-9) << path;
        EXPECT_LT(camera.max_pixel, 1e-9) << path;
        EXPECT_EQ(projector.failures, 0) << path;
        EXPECT_LT(projector.max_normalised, 1e-9) << path;
        EXPECT_LT(projector.max_pixel, 1e-9) << path;
        std::printf("%s: max round trip camera %.3g px, projector %.3g px\n", rig.name.c_str(),
                    camera.max_pixel, projector.max_pixel);
    }
}

TEST(LensModel, UndistortInvertsDistortToMachinePrecision) {
    const LensModel cam = fpp::sim::Rig::paper().camera;
    double worst = 0;
    for (double y = -0.24; y <= 0.24; y += 0.01)
        for (double x = -0.31; x <= 0.31; x += 0.01) {
            Vec2 n{};
            ASSERT_TRUE(cam.undistort(cam.distort({x, y}), n)) << x << " " << y;
            worst = std::max(worst, dist2(n, {x, y}));
        }
    EXPECT_LT(worst, 1e-13);
}

TEST(LensModel, UndistortRejectsNonFiniteAndFoldedInput) {
    const LensModel cam = fpp::sim::Rig::paper().camera;
    Vec2 n{7, 7};
    EXPECT_FALSE(cam.undistort({std::numeric_limits<double>::quiet_NaN(), 0.1}, n));
    EXPECT_FALSE(cam.undistort({std::numeric_limits<double>::infinity(), 0.1}, n));
    // A lens whose radial profile folds back (k1 < 0 strongly): the distorted
    // radius peaks at r = 1/sqrt(3) with value 2/(3 sqrt 3) ~ 0.385; beyond
    // the peak no ray maps there.
    LensModel folded;
    folded.k1 = -1.0;
    EXPECT_FALSE(folded.undistort({0.5, 0.0}, n));
    ASSERT_TRUE(folded.undistort({0.3, 0.0}, n));
    EXPECT_NEAR(folded.distort(n)[0], 0.3, 1e-14);
    EXPECT_LT(n[0], 1 / std::sqrt(3.0)); // the branch that the rays take
}

TEST(Rotation, EulerConventionIsRzRyRx) {
    const double a = -0.42, b = 19.08, c = 0.36;
    const Mat3 R = fpp::rotation_from_euler_deg(a, b, c);
    const Mat3 expected = fpp::mul(
        fpp::rotation_from_euler_deg(0, 0, c),
        fpp::mul(fpp::rotation_from_euler_deg(0, b, 0), fpp::rotation_from_euler_deg(a, 0, 0)));
    for (int i = 0; i < 9; ++i)
        EXPECT_NEAR(R[i], expected[i], 1e-15);
    // Single-axis checks fix the sense of each angle (right-handed).
    const Vec3 x = fpp::mul(fpp::rotation_from_euler_deg(0, 0, 90), Vec3{1, 0, 0});
    EXPECT_NEAR(x[1], 1, 1e-15); // about z: x -> y
    const Vec3 z = fpp::mul(fpp::rotation_from_euler_deg(0, 90, 0), Vec3{0, 0, 1});
    EXPECT_NEAR(z[0], 1, 1e-15); // about y: z -> x
    const Vec3 y = fpp::mul(fpp::rotation_from_euler_deg(90, 0, 0), Vec3{0, 1, 0});
    EXPECT_NEAR(y[2], 1, 1e-15); // about x: y -> z
    // Orthonormal.
    const Mat3 I = fpp::mul(R, fpp::transpose(R));
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            EXPECT_NEAR(I[i * 3 + j], i == j ? 1.0 : 0.0, 1e-15);
}

} // namespace
