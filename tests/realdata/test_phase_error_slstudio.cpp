// The data-only phase-error correction (DecodeOptions::correct_phase_error)
// on SLStudio's real 3-step calibration poses
// (datasets/slstudio/calibration/calseq1..6: a printed 13 x 9 checkerboard,
// 3-step phase of period 114 px + one-period cue along x, 71.25 px + cue
// along y, no white frame; SLStudio's own calibration.xml). Each pose is
// decoded without and with the correction and reconstructed with the
// stereo (SV) model, x only; the board's white squares (found by the corner
// finder on the phase-mean texture; the inner 60 % of each square, away from
// its blurred edges) are judged by their flatness: the RMS distance of their
// points to the least-squares plane through them (camera frame, mm), and,
// independent of the calibration, the residual of a 2D quadratic fit of the
// decoded projector column over the same pixels (projector pixels), with
// the part of it that repeats with the sub-period (114 / 3 px).
//
// Measured (this machine): the correction, estimated from the whole image,
// is 0.07 to 0.08 px RMS along x (mostly the second harmonic of the
// sub-period: the LightCrafter's response is nearly linear), and the
// periodic part of the white squares' column residual drops from
// 0.077..0.087 px to 0.014..0.044 px (mean 0.081 -> 0.027 px; its noise
// floor is about 0.01 px); the whole residual, mostly noise, from
// 0.415..0.495 px to 0.408..0.490 px; the plane RMS of the white squares
// from 0.134 / 0.161 / 0.198 / 0.190 / 0.228 / 0.179 mm to 0.132 / 0.158 /
// 0.195 / 0.188 / 0.225 / 0.176 mm (1.1 to 1.7 % lower: the 3-step phase
// noise and the board's own shape dominate it).

#include "test_support.hpp"

#include "fpp/calib/corners.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/phase_error_correction.hpp"
#include "fpp/point_cloud.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <variant>
#include <vector>

namespace {

constexpr int kColumns = 13, kRows = 9; // inner corners
constexpr double kShrink = 0.6;         // share of each square judged (about its centre)

using fpp::Vec2;

// Pixels inside the inner kShrink of each white square of the board.
std::vector<std::size_t> white_square_pixels(const fpp::calib::CheckerboardCorners& corners,
                                             fpp::Size camera) {
    std::vector<std::size_t> pixels;
    auto corner = [&](int i, int j) {
        return corners.points[static_cast<std::size_t>(j * kColumns + i)];
    };
    for (int b = 0; b + 1 < kRows; ++b)
        for (int a = 0; a + 1 < kColumns; ++a) {
            // Square (a, b) has the colour of square (-1, -1) when a + b is even.
            const bool white = ((a + b) % 2 == 0) != corners.origin_square_black;
            if (!white)
                continue;
            Vec2 q[4] = {corner(a, b), corner(a + 1, b), corner(a + 1, b + 1), corner(a, b + 1)};
            Vec2 centre{0.0, 0.0};
            for (const Vec2& v : q) {
                centre[0] += 0.25 * v[0];
                centre[1] += 0.25 * v[1];
            }
            for (Vec2& v : q) {
                v[0] = centre[0] + kShrink * (v[0] - centre[0]);
                v[1] = centre[1] + kShrink * (v[1] - centre[1]);
            }
            double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
            for (const Vec2& v : q) {
                x0 = std::min(x0, v[0]), x1 = std::max(x1, v[0]);
                y0 = std::min(y0, v[1]), y1 = std::max(y1, v[1]);
            }
            for (int y = std::max(0, int(std::ceil(y0))); y <= std::min(camera.height - 1, int(y1));
                 ++y)
                for (int x = std::max(0, int(std::ceil(x0)));
                     x <= std::min(camera.width - 1, int(x1)); ++x) {
                    // Inside the convex quadrilateral: same side of every edge.
                    int sign = 0;
                    bool inside = true;
                    for (int e = 0; e < 4 && inside; ++e) {
                        const Vec2& p0 = q[e];
                        const Vec2& p1 = q[(e + 1) % 4];
                        const double cross =
                            (p1[0] - p0[0]) * (y - p0[1]) - (p1[1] - p0[1]) * (x - p0[0]);
                        const int s = cross > 0 ? 1 : -1;
                        if (sign == 0)
                            sign = s;
                        else if (s != sign)
                            inside = false;
                    }
                    if (inside)
                        pixels.push_back(std::size_t(y) * std::size_t(camera.width) +
                                         std::size_t(x));
                }
        }
    return pixels;
}

// RMS distance (mm) of the points at `pixels` to their least-squares plane.
double plane_rms(const fpp::PointCloud& cloud, const std::vector<std::size_t>& pixels,
                 std::size_t& used) {
    std::vector<Eigen::Vector3d> pts;
    for (const std::size_t i : pixels) {
        const float* p = cloud.xyz.data() + 3 * i;
        if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
            pts.emplace_back(p[0], p[1], p[2]);
    }
    used = pts.size();
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : pts)
        mean += p;
    mean /= double(pts.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : pts)
        cov += (p - mean) * (p - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    return std::sqrt(eig.eigenvalues()(0) / double(pts.size()));
}

// A 2D quadratic fit of `proj` over `pixels` (the board is flat, so its
// projector column is smooth in the image): the RMS residual, and the RMS of
// the residual's mean in each of 24 bins of the fold of the fitted column
// (the part of the residual that repeats with the sub-period; about 0.01 px
// of noise remains in it with 3000 points a bin). Projector pixels.
struct ColumnFit {
    double residual_rms = 0;
    double periodic_rms = 0;
};

ColumnFit column_fit(const fpp::Image<float>& proj, const std::vector<std::size_t>& pixels,
                     const fpp::PhaseBlock& finest) {
    const auto w = std::size_t(proj.width());
    std::vector<std::size_t> ok;
    for (const std::size_t i : pixels)
        if (std::isfinite(proj.data()[i]))
            ok.push_back(i);
    Eigen::MatrixXd a(ok.size(), 6);
    Eigen::VectorXd b(ok.size());
    for (std::size_t r = 0; r < ok.size(); ++r) {
        const double x = double(ok[r] % w) / 1000.0, y = double(ok[r] / w) / 1000.0;
        a.row(Eigen::Index(r)) << 1, x, y, x * x, x * y, y * y;
        b(Eigen::Index(r)) = proj.data()[ok[r]];
    }
    const Eigen::VectorXd coef = a.colPivHouseholderQr().solve(b);
    const Eigen::VectorXd fitted = a * coef;
    ColumnFit f;
    f.residual_rms = std::sqrt((fitted - b).squaredNorm() / double(ok.size()));
    constexpr int kFoldBins = 24;
    std::vector<double> sum(kFoldBins, 0.0), count(kFoldBins, 0.0);
    for (Eigen::Index r = 0; r < fitted.size(); ++r) {
        const double u = fpp::phase_error_fold(finest, fitted(r));
        const auto bin = std::min<std::size_t>(kFoldBins - 1, std::size_t(u * kFoldBins));
        sum[bin] += b(r) - fitted(r);
        count[bin] += 1;
    }
    double s2 = 0, n = 0;
    for (int k = 0; k < kFoldBins; ++k)
        if (count[std::size_t(k)] > 0) {
            const double mean = sum[std::size_t(k)] / count[std::size_t(k)];
            s2 += count[std::size_t(k)] * mean * mean;
            n += count[std::size_t(k)];
        }
    f.periodic_rms = std::sqrt(s2 / n);
    return f;
}

struct PoseFlatness {
    std::string name;
    double plane_before = 0, plane_after = 0; // mm
    ColumnFit column_before, column_after;    // projector px
    std::size_t points = 0;
    fpp::PhaseErrorSummary x, y;
};

TEST(PhaseErrorSlstudio, CorrectionFlattensTheWhiteSquaresOfTheRealBoards) {
    const auto session = fpp::test::dataset("slstudio/calibration");
    FPP_REQUIRE_DATASET(session);
    const fpp::calib::StereoCalibration calibration = fpp::calib::load_calibration(
        session / "calibration.xml", fpp::calib::CalibrationFormat::slstudio);
    const fpp::calib::SvReconstructor sv(calibration);
    std::vector<PoseFlatness> poses;
    for (int n = 1; n <= 6; ++n) {
        const std::string name = "calseq" + std::to_string(n);
        const fpp::CaptureSet capture = fpp::read_capture_set(session / name);
        const fpp::DecodeResult plain = fpp::decode(capture);
        fpp::DecodeOptions options;
        options.correct_phase_error = true;
        const fpp::DecodeResult corrected = fpp::decode(capture, options);
        const fpp::calib::CheckerboardCorners corners = fpp::calib::find_checkerboard(
            fpp::calib::corner_textures(capture, plain), kColumns, kRows);
        ASSERT_TRUE(corners.found) << name << ": " << corners.failure;
        const std::vector<std::size_t> white =
            white_square_pixels(corners, capture.manifest.camera);
        PoseFlatness f;
        f.name = name;
        f.x = corrected.phase_correction_x;
        f.y = corrected.phase_correction_y;
        fpp::PointCloud before, after;
        sv.reconstruct(plain, fpp::calib::ReconstructAxes::x, before);
        sv.reconstruct(corrected, fpp::calib::ReconstructAxes::x, after);
        std::size_t used_before = 0;
        f.plane_before = plane_rms(before, white, used_before);
        f.plane_after = plane_rms(after, white, f.points);
        const fpp::PhaseBlock finest_x = std::get<fpp::PhaseBlock>(capture.manifest.sequence[0]);
        f.column_before = column_fit(plain.proj_x, white, finest_x);
        f.column_after = column_fit(corrected.proj_x, white, finest_x);
        std::printf("[ figures  ] %s: white squares %zu points: plane RMS %.4f -> %.4f mm; "
                    "projector column about a quadratic %.4f -> %.4f px, its periodic part "
                    "%.4f -> %.4f px\n"
                    "[ figures  ]   x: %s\n[ figures  ]   y: %s\n",
                    name.c_str(), f.points, f.plane_before, f.plane_after,
                    f.column_before.residual_rms, f.column_after.residual_rms,
                    f.column_before.periodic_rms, f.column_after.periodic_rms,
                    fpp::describe(f.x).c_str(), fpp::describe(f.y).c_str());
        EXPECT_EQ(used_before, f.points) << name; // the correction keeps validity
        EXPECT_TRUE(f.x.applied) << name << ": " << f.x.reason;
        EXPECT_LT(f.plane_after, f.plane_before) << name;
        EXPECT_LT(f.column_after.residual_rms, f.column_before.residual_rms) << name;
        EXPECT_LT(f.column_after.periodic_rms, 0.6 * f.column_before.periodic_rms) << name;
        poses.push_back(f);
    }
    double plane_gain = 0, periodic_before = 0, periodic_after = 0;
    for (const PoseFlatness& f : poses) {
        plane_gain += (f.plane_before - f.plane_after) / f.plane_before / double(poses.size());
        periodic_before += f.column_before.periodic_rms / double(poses.size());
        periodic_after += f.column_after.periodic_rms / double(poses.size());
    }
    std::printf("[ figures  ] over the six poses: white squares' plane RMS %.2f %% lower; "
                "periodic part of the column residual %.4f -> %.4f px\n",
                100 * plane_gain, periodic_before, periodic_after);
    EXPECT_GT(plane_gain, 0.01);
    EXPECT_LT(periodic_after, 0.5 * periodic_before);
}

} // namespace
