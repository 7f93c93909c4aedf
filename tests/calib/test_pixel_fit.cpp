// The hybrid table's per-pixel fits on synthetic samples. Eight tilted
// board planes; each pixel's phase at a pose is where a known per-pixel
// function of the phase reaches the depth at which the pixel's ray meets the
// plane: a cubic Z(p) (fitted exactly by the polynomial and ray models) or a
// ratio of linear functions Z(p) = (A + B p) / (1 + E p) (the pinhole case,
// fitted exactly by the rational model). The coefficients the table holds
// are compared with the truth rewritten in the pixel's normalised phase t,
// and the fitted function with the truth at every sample phase. Pixels with
// too few samples, no ray or all samples at one phase get no model and are
// counted as such.

#include "fpp/calib/pixel_fit.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace {

using fpp::CoefficientTable;
using fpp::Image;
using fpp::TableInfo;
using fpp::TableModel;
using fpp::calib::PixelFit;
using fpp::calib::PixelFitOptions;
using fpp::calib::PoseSamples;
namespace plane = fpp::table_plane;

constexpr int kWidth = 16, kHeight = 8, kPoses = 8;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// Depth tolerance: 1e-6 of the ~500 mm depths.
constexpr double kDepthTol = 5e-4;

// Special pixels.
constexpr int kFewU = 3, kFewV = 2;          // 5 samples: one too few
constexpr int kEnoughU = 10, kEnoughV = 5;   // 6 samples: just enough
constexpr int kNoRayU = 15, kNoRayV = 7;     // no camera ray: no sample
constexpr int kBunchedU = 12, kBunchedV = 1; // every sample at one phase

bool special(int u, int v) {
    return (u == kFewU && v == kFewV) || (u == kNoRayU && v == kNoRayV) ||
           (u == kBunchedU && v == kBunchedV);
}

double ray_x(int u) {
    return double(static_cast<float>((u - 7.5) * 0.01));
}
double ray_y(int v) {
    return double(static_cast<float>((v - 3.5) * 0.012));
}

Image<float> camera_rays() {
    Image<float> rays(kWidth, kHeight, 2);
    for (int v = 0; v < kHeight; ++v)
        for (int u = 0; u < kWidth; ++u) {
            const bool none = u == kNoRayU && v == kNoRayV;
            rays.at(u, v, 0) = none ? kNaN : static_cast<float>(ray_x(u));
            rays.at(u, v, 1) = none ? kNaN : static_cast<float>(ray_y(v));
        }
    return rays;
}

fpp::calib::BoardPlane board(int k) {
    const double nx = 0.02 * (k % 3 - 1), ny = 0.015 * ((k % 2) * 2 - 1);
    const double len = std::sqrt(nx * nx + ny * ny + 1);
    return {fpp::Vec3{nx / len, ny / len, 1 / len}, 430 + 16.0 * k};
}

// Where pixel (u, v)'s ray meets pose k's board.
double depth(int k, int u, int v) {
    const fpp::calib::BoardPlane b = board(k);
    return b.d / (b.normal[0] * ray_x(u) + b.normal[1] * ray_y(v) + b.normal[2]);
}

// Truth of the cubic kind: Z = z0 + s x + q x^2 + r x^3, x = p - 400,
// decreasing over the phases used.
struct Cubic {
    double z0, s, q, r;
    double operator()(double p) const {
        const double x = p - 400;
        return z0 + x * (s + x * (q + x * r));
    }
    // In t, for p = c + h t: coefficients of 1, t, t^2, t^3.
    std::array<double, 4> in_t(double c, double h) const {
        const double e = c - 400;
        return {(*this)(c), h * (s + 2 * q * e + 3 * r * e * e), h * h * (q + 3 * r * e),
                h * h * h * r};
    }
};

Cubic cubic_truth(int u, int v) {
    return {486 + 0.3 * u, -0.25, 1e-5 * (1 + 0.05 * v), -2e-7};
}

// Truth of the rational kind: Z = (A + B p) / (1 + E p).
struct Rational {
    double A, B, E;
    double operator()(double p) const { return (A + B * p) / (1 + E * p); }
    double phase_at(double z) const { return (A - z) / (E * z - B); }
    // In t, for p = c + h t: Z = (z0 + z1 t) / (1 + d t); returns z0, z1, d.
    std::array<double, 3> in_t(double c, double h) const {
        const double den = 1 + E * c;
        return {(A + B * c) / den, B * h / den, E * h / den};
    }
};

Rational rational_truth(int u, int v) {
    return {700 + 0.5 * u, 0.05 - 0.001 * v, 1e-3 * (1 + 0.02 * u)};
}

// The phase at which the decreasing cubic reaches depth z, by bisection.
double cubic_phase_at(const Cubic& f, double z) {
    double lo = 0, hi = 800;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (f(mid) > z ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

// The samples of every pose, with the special pixels' gaps.
std::vector<PoseSamples> poses_for(bool rational) {
    std::vector<PoseSamples> poses(kPoses);
    for (int k = 0; k < kPoses; ++k) {
        PoseSamples& s = poses[static_cast<std::size_t>(k)];
        s.phase = Image<float>(kWidth, kHeight, 1, kNaN);
        s.plane = board(k);
        for (int v = 0; v < kHeight; ++v)
            for (int u = 0; u < kWidth; ++u) {
                if (u == kFewU && v == kFewV && k < 3)
                    continue; // 5 samples left
                if (u == kEnoughU && v == kEnoughV && k >= 6)
                    continue; // 6 samples left
                const double z = depth(k, u, v);
                const double p = rational ? rational_truth(u, v).phase_at(z)
                                          : cubic_phase_at(cubic_truth(u, v), z);
                s.phase.at(u, v) = static_cast<float>(p);
                if (u == kBunchedU && v == kBunchedV)
                    s.phase.at(u, v) = 321.5f;
            }
    }
    return poses;
}

TableInfo table_info(TableModel model) {
    TableInfo info;
    info.camera = {kWidth, kHeight};
    info.tile_width = 8;
    info.tile_height = 8;
    info.model = model;
    info.projector = {912, 1140};
    return info;
}

PixelFit fit(TableModel model, bool rational_truth_samples) {
    PixelFitOptions options;
    options.model = model;
    options.threads = 2;
    return fpp::calib::fit_pixel_models(poses_for(rational_truth_samples), camera_rays(),
                                        table_info(model), options);
}

// The table's point at phase p of pixel (u, v): X, Y, Z.
std::array<double, 3> evaluate(const CoefficientTable& table, int u, int v, double p) {
    const auto c = [&](int index) { return double(table.get(index, u, v)); };
    const double t = (p - c(plane::centre)) * c(plane::inv_half_range);
    const auto cubic_at = [&](int first) {
        double sum = 0;
        for (int k = 3; k >= 0; --k)
            sum = sum * t + c(first + k);
        return sum;
    };
    switch (table.info().model) {
    case TableModel::polynomial:
        return {cubic_at(plane::poly_x), cubic_at(plane::poly_y), cubic_at(plane::poly_z)};
    case TableModel::ray: {
        const double z = cubic_at(plane::ray_z);
        return {c(plane::ray_xn) * z, c(plane::ray_yn) * z, z};
    }
    case TableModel::rational:
        break;
    }
    const double z = cubic_at(plane::rational_z) / (1 + c(plane::rational_d) * t);
    return {c(plane::rational_xn) * z, c(plane::rational_yn) * z, z};
}

// The phase range of pixel (u, v)'s samples: centre and half width.
std::array<double, 2> phase_range(const std::vector<PoseSamples>& poses, int u, int v) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const PoseSamples& s : poses) {
        const double p = s.phase.at(u, v);
        if (std::isfinite(p)) {
            lo = std::min(lo, p);
            hi = std::max(hi, p);
        }
    }
    return {0.5 * (lo + hi), 0.5 * (hi - lo)};
}

void expect_special_pixels(const PixelFit& f) {
    EXPECT_EQ(f.modelled, std::size_t(kWidth * kHeight - 3));
    EXPECT_EQ(f.too_few, 2u); // the 5-sample pixel and the one without a ray
    EXPECT_EQ(f.ill_conditioned, 1u);
    EXPECT_EQ(f.samples.at(kFewU, kFewV), 5);
    EXPECT_EQ(f.samples.at(kEnoughU, kEnoughV), 6);
    EXPECT_EQ(f.samples.at(kNoRayU, kNoRayV), 0);
    EXPECT_EQ(f.samples.at(kBunchedU, kBunchedV), kPoses);
    EXPECT_EQ(f.samples.at(0, 0), kPoses);
    for (const auto& [u, v] :
         {std::pair{kFewU, kFewV}, {kNoRayU, kNoRayV}, {kBunchedU, kBunchedV}}) {
        EXPECT_FALSE(f.table.has_model(u, v)) << u << "," << v;
        EXPECT_TRUE(std::isnan(f.table.get(plane::centre, u, v))) << u << "," << v;
        EXPECT_TRUE(std::isnan(f.rms_z.at(u, v))) << u << "," << v;
        EXPECT_TRUE(std::isnan(f.sigma_z.at(u, v))) << u << "," << v;
    }
    EXPECT_TRUE(f.table.has_model(kEnoughU, kEnoughV));
}

TEST(ModelCoefficients, PerModel) {
    EXPECT_EQ(fpp::calib::model_coefficients(TableModel::polynomial), 4);
    EXPECT_EQ(fpp::calib::model_coefficients(TableModel::ray), 4);
    EXPECT_EQ(fpp::calib::model_coefficients(TableModel::rational), 5);
}

TEST(FitPixelModels, RayModelRecoversACubicPerPixel) {
    const PixelFit f = fit(TableModel::ray, false);
    expect_special_pixels(f);
    const std::vector<PoseSamples> poses = poses_for(false);
    for (int v = 0; v < kHeight; ++v)
        for (int u = 0; u < kWidth; ++u) {
            if (special(u, v))
                continue;
            ASSERT_TRUE(f.table.has_model(u, v)) << u << "," << v;
            const auto [c, h] = phase_range(poses, u, v);
            EXPECT_NEAR(f.table.get(plane::centre, u, v), c, 1e-4) << u << "," << v;
            EXPECT_NEAR(f.table.get(plane::inv_half_range, u, v), 1 / h, 1e-6 / h);
            const std::array<double, 4> truth = cubic_truth(u, v).in_t(c, h);
            for (int k = 0; k < 4; ++k)
                EXPECT_NEAR(f.table.get(plane::ray_z + k, u, v), truth[std::size_t(k)], kDepthTol)
                    << u << "," << v << " Z" << k;
            EXPECT_FLOAT_EQ(f.table.get(plane::ray_xn, u, v), float(ray_x(u)));
            EXPECT_FLOAT_EQ(f.table.get(plane::ray_yn, u, v), float(ray_y(v)));
            for (int k = 0; k < kPoses; ++k) {
                const double p = poses[std::size_t(k)].phase.at(u, v);
                if (!std::isfinite(p))
                    continue;
                const double z = cubic_truth(u, v)(p);
                const auto xyz = evaluate(f.table, u, v, p);
                EXPECT_NEAR(xyz[2], z, kDepthTol) << u << "," << v << " pose " << k;
                EXPECT_NEAR(xyz[0], ray_x(u) * z, kDepthTol) << u << "," << v << " pose " << k;
                EXPECT_NEAR(xyz[1], ray_y(v) * z, kDepthTol) << u << "," << v << " pose " << k;
            }
            EXPECT_LT(f.rms_z.at(u, v), 1e-4) << u << "," << v;
            EXPECT_LT(f.sigma_z.at(u, v), 1e-4) << u << "," << v;
        }
}

TEST(FitPixelModels, PolynomialModelRecoversXYZCubics) {
    const PixelFit f = fit(TableModel::polynomial, false);
    expect_special_pixels(f);
    const std::vector<PoseSamples> poses = poses_for(false);
    for (int v = 0; v < kHeight; ++v)
        for (int u = 0; u < kWidth; ++u) {
            if (special(u, v))
                continue;
            const auto [c, h] = phase_range(poses, u, v);
            const std::array<double, 4> truth = cubic_truth(u, v).in_t(c, h);
            for (int k = 0; k < 4; ++k) {
                const double z = truth[std::size_t(k)];
                EXPECT_NEAR(f.table.get(plane::poly_z + k, u, v), z, kDepthTol)
                    << u << "," << v << " Z" << k;
                // X = xn Z and Y = yn Z along the ray: the same cubic scaled.
                EXPECT_NEAR(f.table.get(plane::poly_x + k, u, v), ray_x(u) * z, kDepthTol)
                    << u << "," << v << " X" << k;
                EXPECT_NEAR(f.table.get(plane::poly_y + k, u, v), ray_y(v) * z, kDepthTol)
                    << u << "," << v << " Y" << k;
            }
            const double p =
                0.5 * (double(poses[0].phase.at(u, v)) + double(poses[1].phase.at(u, v)));
            const double z = cubic_truth(u, v)(p);
            const auto xyz = evaluate(f.table, u, v, p); // between two samples
            EXPECT_NEAR(xyz[2], z, kDepthTol) << u << "," << v;
            EXPECT_NEAR(xyz[0], ray_x(u) * z, kDepthTol) << u << "," << v;
            EXPECT_LT(f.rms_x.at(u, v), 1e-4) << u << "," << v;
            EXPECT_LT(f.rms_y.at(u, v), 1e-4) << u << "," << v;
        }
}

TEST(FitPixelModels, RationalModelRecoversARatioOfLinearFunctions) {
    const PixelFit f = fit(TableModel::rational, true);
    expect_special_pixels(f);
    const std::vector<PoseSamples> poses = poses_for(true);
    for (int v = 0; v < kHeight; ++v)
        for (int u = 0; u < kWidth; ++u) {
            if (special(u, v))
                continue;
            const auto [c, h] = phase_range(poses, u, v);
            const std::array<double, 3> truth = rational_truth(u, v).in_t(c, h);
            EXPECT_NEAR(f.table.get(plane::rational_z, u, v), truth[0], kDepthTol) << u << "," << v;
            // Z1..Z3 and d trade against each other along a nearly flat
            // direction of the least squares (t Z is close to a cubic in t),
            // and the samples' phases, rounded to float, put about 1e-5 mm
            // on each depth: they come back to about 1e-3 relative where
            // the function itself (below) comes back to 1e-6.
            EXPECT_NEAR(f.table.get(plane::rational_z + 1, u, v), truth[1],
                        0.01 * std::fabs(truth[1]))
                << u << "," << v;
            EXPECT_NEAR(f.table.get(plane::rational_z + 2, u, v), 0, 0.01) << u << "," << v;
            EXPECT_NEAR(f.table.get(plane::rational_z + 3, u, v), 0, 0.01) << u << "," << v;
            EXPECT_NEAR(f.table.get(plane::rational_d, u, v), truth[2], 1e-3 * truth[2])
                << u << "," << v;
            // The denominator is not negligible: a cubic alone would not do.
            EXPECT_GT(std::fabs(truth[2]), 0.05) << u << "," << v;
            EXPECT_FLOAT_EQ(f.table.get(plane::rational_xn, u, v), float(ray_x(u)));
            EXPECT_FLOAT_EQ(f.table.get(plane::rational_yn, u, v), float(ray_y(v)));
            for (int k = 0; k < kPoses; ++k) {
                const double p = poses[std::size_t(k)].phase.at(u, v);
                if (!std::isfinite(p))
                    continue;
                const double z = rational_truth(u, v)(p);
                const auto xyz = evaluate(f.table, u, v, p);
                EXPECT_NEAR(xyz[2], z, kDepthTol) << u << "," << v << " pose " << k;
                EXPECT_NEAR(xyz[1], ray_y(v) * z, kDepthTol) << u << "," << v << " pose " << k;
            }
            EXPECT_LT(f.rms_z.at(u, v), 1e-4) << u << "," << v;
        }
}

TEST(FitPixelModels, CubicModelsCannotFollowTheRationalTruth) {
    // The same rational samples fitted by the ray model's cubic leave a
    // residual far above the rational model's.
    const PixelFit cubic = fit(TableModel::ray, true);
    const PixelFit rational = fit(TableModel::rational, true);
    EXPECT_GT(cubic.rms_z.at(0, 0), 100 * rational.rms_z.at(0, 0));
    EXPECT_GT(cubic.rms_z.at(0, 0), 1e-4);
}

TEST(FitPixelModels, MinSamplesOptionDecidesWhoIsTooFew) {
    PixelFitOptions options;
    options.model = TableModel::ray;
    options.threads = 2;
    options.min_samples = 7;
    const PixelFit f = fpp::calib::fit_pixel_models(poses_for(false), camera_rays(),
                                                    table_info(TableModel::ray), options);
    // Now the 6-sample pixel is one too few as well.
    EXPECT_EQ(f.too_few, 3u);
    EXPECT_FALSE(f.table.has_model(kEnoughU, kEnoughV));
    EXPECT_EQ(f.samples.at(kEnoughU, kEnoughV), 6);
    EXPECT_EQ(f.modelled, std::size_t(kWidth * kHeight - 4));
}

TEST(FitPixelModels, RejectsInputsThatDoNotFit) {
    const TableInfo info = table_info(TableModel::ray);
    PixelFitOptions options;
    options.threads = 2;
    // Rays of another size.
    EXPECT_THROW(
        fpp::calib::fit_pixel_models(poses_for(false), Image<float>(8, 8, 2), info, options),
        std::invalid_argument);
    // Rays with one channel.
    EXPECT_THROW(fpp::calib::fit_pixel_models(poses_for(false), Image<float>(kWidth, kHeight, 1),
                                              info, options),
                 std::invalid_argument);
    // A pose of another size.
    std::vector<PoseSamples> poses = poses_for(false);
    poses[3].phase = Image<float>(kWidth, kHeight - 1);
    EXPECT_THROW(fpp::calib::fit_pixel_models(poses, camera_rays(), info, options),
                 std::invalid_argument);
    // The paper's correction without SV depth.
    options.correction = fpp::calib::PlaneCorrection::perpendicular_foot;
    EXPECT_THROW(fpp::calib::fit_pixel_models(poses_for(false), camera_rays(), info, options),
                 std::invalid_argument);
    // Board samples weighted 0 and no model samples: nothing to fit.
    options.correction = fpp::calib::PlaneCorrection::along_ray;
    options.board_weight = 0;
    EXPECT_THROW(fpp::calib::fit_pixel_models(poses_for(false), camera_rays(), info, options),
                 std::invalid_argument);
}

} // namespace
