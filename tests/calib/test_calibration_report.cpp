// The stereo calibration report's pure parts: Euler angles of a rotation
// (the header's convention R = Rz(c) Ry(b) Rx(a), angles in degrees, returned
// as (a, b, c)) and the Markdown summary of a small hand-made SessionResult,
// checked line by line for the figures it prints.

#include "fpp/calib/calibration_report.hpp"
#include "fpp/calib/stereo_session.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace {

using fpp::Mat3;
using fpp::Vec3;
using fpp::calib::euler_deg_from_rotation;

constexpr double kPi = 3.14159265358979323846;

// Row-major 3 x 3 product.
Mat3 multiply(const Mat3& x, const Mat3& y) {
    Mat3 r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double sum = 0;
            for (int k = 0; k < 3; ++k)
                sum +=
                    x[static_cast<std::size_t>(3 * i + k)] * y[static_cast<std::size_t>(3 * k + j)];
            r[static_cast<std::size_t>(3 * i + j)] = sum;
        }
    return r;
}

Mat3 rot_x(double deg) {
    const double t = deg * kPi / 180, c = std::cos(t), s = std::sin(t);
    return {1, 0, 0, 0, c, -s, 0, s, c};
}
Mat3 rot_y(double deg) {
    const double t = deg * kPi / 180, c = std::cos(t), s = std::sin(t);
    return {c, 0, s, 0, 1, 0, -s, 0, c};
}
Mat3 rot_z(double deg) {
    const double t = deg * kPi / 180, c = std::cos(t), s = std::sin(t);
    return {c, -s, 0, s, c, 0, 0, 0, 1};
}

// R = Rz(c) Ry(b) Rx(a): a about x first, then b about y, then c about z.
Mat3 from_euler(double a, double b, double c) {
    return multiply(rot_z(c), multiply(rot_y(b), rot_x(a)));
}

TEST(EulerDegFromRotation, IdentityGivesZeros) {
    const Vec3 e = euler_deg_from_rotation(Mat3{1, 0, 0, 0, 1, 0, 0, 0, 1});
    EXPECT_EQ(e[0], 0.0);
    EXPECT_EQ(e[1], 0.0);
    EXPECT_EQ(e[2], 0.0);
}

TEST(EulerDegFromRotation, SingleAxisRotationsGiveTheirOwnAngle) {
    const Vec3 ex = euler_deg_from_rotation(rot_x(25));
    EXPECT_NEAR(ex[0], 25, 1e-12);
    EXPECT_NEAR(ex[1], 0, 1e-12);
    EXPECT_NEAR(ex[2], 0, 1e-12);
    const Vec3 ey = euler_deg_from_rotation(rot_y(-40));
    EXPECT_NEAR(ey[0], 0, 1e-12);
    EXPECT_NEAR(ey[1], -40, 1e-12);
    EXPECT_NEAR(ey[2], 0, 1e-12);
    const Vec3 ez = euler_deg_from_rotation(rot_z(130));
    EXPECT_NEAR(ez[0], 0, 1e-12);
    EXPECT_NEAR(ez[1], 0, 1e-12);
    EXPECT_NEAR(ez[2], 130, 1e-12);
}

TEST(EulerDegFromRotation, KnownAnglesRoundTrip) {
    // b stays inside (-90, 90), where the decomposition is unique; a and c
    // cover all four quadrants.
    const double cases[][3] = {{10, 20, 30},     {-35.5, 12.25, 170},    {120, -60, -95},
                               {-170, 85, 45.5}, {0.001, -0.002, 0.003}, {179, -1, -179}};
    for (const auto& c : cases) {
        const Vec3 e = euler_deg_from_rotation(from_euler(c[0], c[1], c[2]));
        EXPECT_NEAR(e[0], c[0], 1e-9) << c[0] << " " << c[1] << " " << c[2];
        EXPECT_NEAR(e[1], c[1], 1e-9) << c[0] << " " << c[1] << " " << c[2];
        EXPECT_NEAR(e[2], c[2], 1e-9) << c[0] << " " << c[1] << " " << c[2];
    }
}

TEST(EulerDegFromRotation, OrderMattersRzRyRxNotRxRyRz) {
    // The same three angles composed the other way round are a different
    // rotation, which must not decompose to them.
    const Mat3 other = multiply(rot_x(30), multiply(rot_y(40), rot_z(50)));
    const Vec3 e = euler_deg_from_rotation(other);
    EXPECT_GT(std::abs(e[0] - 30) + std::abs(e[1] - 40) + std::abs(e[2] - 50), 1.0);
    // and its own decomposition rebuilds it
    const Mat3 back = from_euler(e[0], e[1], e[2]);
    for (std::size_t k = 0; k < 9; ++k)
        EXPECT_NEAR(back[k], other[k], 1e-12) << k;
}

// A session of three poses: two calibrated (one of them dropped as an
// outlier), one skipped; distinctive figures everywhere.
fpp::calib::SessionResult small_session() {
    using namespace fpp::calib;
    SessionResult r;
    r.folder = "sessions/bench-7";
    r.board.inner_columns = 9;
    r.board.inner_rows = 6;
    r.board.square_size = 12.5;
    r.camera_size = {1280, 1024};
    r.projector_size = {912, 1140};
    r.method = CornerMethod::poly;

    SessionPose a;
    a.name = "pose-01";
    a.usable = true;
    a.corners.found = true;
    a.corners.finder = "sector";
    a.corners.texture = "white";
    a.projector[0].valid.assign(54, true);
    a.projector[0].valid[3] = false;
    a.projector[0].failed = 1;
    SessionPose b = a;
    b.name = "pose-02";
    b.projector[0].valid.assign(54, true);
    b.projector[0].failed = 0;
    SessionPose c;
    c.name = "pose-03";
    c.usable = false;
    c.skip_reason = "board not found";
    r.poses = {a, b, c};
    r.calibrated = {0, 1};

    StereoResult& s = r.stereo;
    s.initial_camera_rms = 0.31416;
    s.initial_projector_rms = 0.27183;
    s.iterations = 17;
    s.skew_estimated = false;
    s.procedure = StereoProcedure::joint;
    StereoCalibration& cal = s.calibration;
    cal.camera_rms = 0.12346;
    cal.projector_rms = 0.06789;
    cal.camera.fu = 2400.123;
    cal.camera.fv = 2401.987;
    cal.camera.cu = 640.5;
    cal.camera.cv = 511.25;
    cal.camera.k1 = -0.123456;
    cal.projector.fu = 1800.5;
    cal.projector.p2 = 0.0001234;
    cal.projector.fv = 1799.75;
    // LensModel's defaults are fu = fv = 1: set every sigma the test reads.
    s.camera_sigma.fu = 0.25;
    s.camera_sigma.fv = 0.5;
    s.projector_sigma.fu = 0.125;
    s.projector_sigma.fv = 0.0625;
    cal.R = from_euler(1.5, -2.25, 0.75);
    cal.T = {-150.0, 2.5, 10.0};
    cal.poses.push_back({"pose-01", 0.1111, 0.0555, 54, true, ""});
    cal.poses.push_back({"pose-02", 0.9876, 1.2345, 54, false, "outlier: projector RMS 1.23 px"});
    r.seconds_decode = 1.234;
    r.seconds_corners = 0.5;
    r.seconds_calibration = 2.0;
    r.seconds_total = 3.75;
    return r;
}

bool has_line(const std::string& text, const std::string& line) {
    return text.find(line + "\n") != std::string::npos;
}

TEST(CalibrationSummary, SessionHeaderAndReprojectionFigures) {
    const std::string md = fpp::calib::calibration_summary(small_session());
    EXPECT_EQ(md.rfind("# Stereo calibration\n\n", 0), 0u) << md;
    EXPECT_TRUE(has_line(md, "Session: `sessions/bench-7`  ")) << md;
    EXPECT_TRUE(has_line(md, "Board: 9 x 6 inner corners, 12.500 mm squares  ")) << md;
    EXPECT_TRUE(has_line(md, "Camera 1280 x 1024 px, projector 912 x 1140 px  ")) << md;
    EXPECT_TRUE(has_line(md, "Poses: 3 found, 2 usable; projector coordinates of the corners by "
                             "`poly`; skew fixed at 0"))
        << md;
    EXPECT_TRUE(has_line(md, "| OpenCV initialisation (per device, skew 0) | 0.3142 | 0.2718 |"))
        << md;
    EXPECT_TRUE(has_line(md, "| joint bundle adjustment, skew fixed at 0 (saved) | 0.1235 | "
                             "0.0679 |"))
        << md;
    // no comparison row without other_skew
    EXPECT_EQ(md.find("(comparison)"), std::string::npos) << md;
    EXPECT_TRUE(has_line(md, "LM iterations: 17")) << md;
    EXPECT_TRUE(has_line(md, "Correction grids: camera none; projector none.  ")) << md;
    // dense_rms < 0: no dense line
    EXPECT_EQ(md.find("Dense samples"), std::string::npos) << md;
}

TEST(CalibrationSummary, PoseTableRows) {
    const std::string md = fpp::calib::calibration_summary(small_session());
    EXPECT_TRUE(has_line(md, "| pose-01 | sector | white | 53/54 | 0.1111 | 0.0555 | used |"))
        << md;
    EXPECT_TRUE(has_line(md, "| pose-02 | sector | white | 54/54 | 0.9876 | 1.2345 | dropped: "
                             "outlier: projector RMS 1.23 px |"))
        << md;
    EXPECT_TRUE(has_line(md, "| pose-03 | - | - | - | - | - | skipped: board not found |")) << md;
}

TEST(CalibrationSummary, IntrinsicsExtrinsicsAndTiming) {
    const std::string md = fpp::calib::calibration_summary(small_session());
    EXPECT_TRUE(has_line(md, "| fu (px) | 2400.12 | 0.25 | 1800.50 | 0.125 |")) << md;
    EXPECT_TRUE(has_line(md, "| fv (px) | 2401.99 | 0.5 | 1799.75 | 0.0625 |")) << md;
    EXPECT_TRUE(has_line(md, "| cv (px) | 511.25 | 0 | 0.00 | 0 |")) << md;
    EXPECT_TRUE(has_line(md, "| k1 | -0.12346 | 0 | 0.00000 | 0 |")) << md;
    EXPECT_TRUE(has_line(md, "| p2 | 0.000000 | 0 | 0.000123 | 0 |")) << md;
    EXPECT_TRUE(has_line(md, "R as Euler angles (R = Rz(c) Ry(b) Rx(a)): a 1.5000, b -2.2500, c "
                             "0.7500 deg  "))
        << md;
    EXPECT_TRUE(has_line(md, "T: -150.000, 2.500, 10.000 mm  ")) << md;
    // The projector centre -R^T T, and its distance from the camera.
    const fpp::calib::SessionResult r = small_session();
    const Vec3 centre = r.stereo.calibration.projector_centre();
    char expected[200];
    std::snprintf(expected, sizeof expected,
                  "Projector centre in the camera frame: %.2f, %.2f, %.2f mm (baseline %.2f mm)",
                  centre[0], centre[1], centre[2],
                  std::sqrt(centre[0] * centre[0] + centre[1] * centre[1] + centre[2] * centre[2]));
    EXPECT_TRUE(has_line(md, expected)) << md;
    // |T| = sqrt(150^2 + 2.5^2 + 10^2), unchanged by the rotation.
    EXPECT_NE(md.find("(baseline 150.35 mm)"), std::string::npos) << md;
    EXPECT_TRUE(has_line(md, "Predicted trueness: unknown (not computed for this calibration)."))
        << md;
    EXPECT_TRUE(has_line(md, "decoding 1.23 s, corners 0.50 s, calibration 2.00 s, total 3.75 s"))
        << md;
    // No simulator truth, no held-out check: neither section.
    EXPECT_EQ(md.find("against ground truth"), std::string::npos) << md;
    EXPECT_EQ(md.find("## Held-out poses"), std::string::npos) << md;
}

TEST(CalibrationSummary, HeldOutSectionWhenGiven) {
    fpp::calib::HeldOutCheck h;
    fpp::calib::HeldOutPose p;
    p.name = "pose-02";
    p.corners = 54;
    p.distance_mm = 487.31;
    p.fit_rms_mm = 0.01234;
    p.scale_error = 12.34e-6;
    p.length_rms_mm = 0.0201;
    p.length_max_mm = 0.0456;
    h.poses.push_back(p);
    h.fit_rms_mm = 0.01234;
    h.scale_error_rms = 12.34e-6;
    h.length_rms_mm = 0.0201;
    h.length_max_mm = 0.0456;
    const std::string md = fpp::calib::calibration_summary(small_session(), &h);
    EXPECT_NE(md.find("\n## Held-out poses\n"), std::string::npos) << md;
    EXPECT_TRUE(has_line(md, "| pose-02 | 54 | 487.3 | 0.0123 | 12.3 | 0.0201 | 0.0456 |")) << md;
    EXPECT_TRUE(has_line(md, "| all | | | **0.0123** | 12.3 (RMS) | **0.0201** | **0.0456** |"))
        << md;
    // The timing comes after it.
    EXPECT_LT(md.find("## Held-out poses"), md.find("## Timing")) << md;
}

} // namespace
