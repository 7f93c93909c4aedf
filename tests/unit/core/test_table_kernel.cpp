// The reconstruction kernel against a double-precision evaluation of the same
// coefficients, with a rounding-error bound per pixel; the pixels without a
// point and their counts; thread and tiling independence.

#include "fpp/coefficient_table.hpp"
#include "fpp/parallel.hpp"
#include "fpp/table_kernel.hpp"

#include "synthetic_table.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace {

using fpp::test::kSyntheticCamera;
using fpp::test::synthetic_has_model;
using fpp::test::synthetic_pixel;
using fpp::test::synthetic_table;
using fpp::test::SyntheticPixel;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kU = 0x1p-24; // unit roundoff of float

// Phase per pixel, by kind: in range (|s| <= 0.97 of the half range), out of
// range (1.02..1.5), NaN and infinite.
enum class Kind { in_range, out_of_range, nan, infinite };

Kind kind_of(int x, int y) {
    const int k = (x * 13 + y * 5) % 41;
    if (k == 0)
        return Kind::nan;
    if (k == 1)
        return Kind::infinite;
    if (k == 2 || k == 3)
        return Kind::out_of_range;
    return Kind::in_range;
}

fpp::Image<float> make_phase() {
    fpp::Image<float> phase(kSyntheticCamera, 1);
    for (int y = 0; y < kSyntheticCamera.height; ++y) {
        for (int x = 0; x < kSyntheticCamera.width; ++x) {
            const SyntheticPixel p = synthetic_pixel(x, y);
            const double half = 1.0 / p.ihr;
            const double s = std::sin(0.37 * x + 0.11 * y);
            float v = 0.0f;
            switch (kind_of(x, y)) {
            case Kind::in_range:
                v = float(p.centre + 0.97 * s * half);
                break;
            case Kind::out_of_range:
                v = float(p.centre + (s >= 0 ? 1.0 : -1.0) * (1.02 + 0.48 * std::fabs(s)) * half);
                break;
            case Kind::nan:
                v = kNaN;
                break;
            case Kind::infinite:
                v = (x % 2 ? 1.0f : -1.0f) * std::numeric_limits<float>::infinity();
                break;
            }
            phase.at(x, y) = v;
        }
    }
    return phase;
}

struct Horner {
    double value;
    double bound; // first-order float rounding bound of the kernel's evaluation
};

// c0 + c1 t + c2 t^2 + c3 t^3 in double, with the float kernel's error bound:
// Horner's 6 roundings give at most gamma_6 * sum |c_k| |t|^k, and t's own 2
// roundings (|dt| <= gamma_2 |t|) add |Z'(t)| gamma_2 |t|.
Horner horner(const float* cf, double t) {
    const double c[4] = {double(cf[0]), double(cf[1]), double(cf[2]), double(cf[3])};
    const double value = ((c[3] * t + c[2]) * t + c[1]) * t + c[0];
    const double at = std::fabs(t);
    const double magnitude = std::fabs(c[0]) + std::fabs(c[1]) * at + std::fabs(c[2]) * at * at +
                             std::fabs(c[3]) * at * at * at;
    const double slope = std::fabs(c[1] + 2.0 * c[2] * t + 3.0 * c[3] * t * t);
    const double g6 = 6 * kU / (1 - 6 * kU);
    const double g2 = 2 * kU / (1 - 2 * kU);
    return {value, g6 * magnitude + g2 * at * slope};
}

// The counts by the definitions of TableApplyStats, in double.
fpp::TableApplyStats expected_stats(const fpp::CoefficientTable& table,
                                    const fpp::Image<float>& phase) {
    fpp::TableApplyStats s;
    for (int y = 0; y < kSyntheticCamera.height; ++y) {
        for (int x = 0; x < kSyntheticCamera.width; ++x) {
            const double p = double(phase.at(x, y));
            if (!std::isfinite(p))
                continue;
            ++s.phase_valid;
            if (!table.has_model(x, y)) {
                ++s.no_model;
                continue;
            }
            const double t = (p - double(table.get(fpp::table_plane::centre, x, y))) *
                             double(table.get(fpp::table_plane::inv_half_range, x, y));
            if (std::fabs(t) <= 1.0)
                ++s.points;
            else
                ++s.out_of_range;
        }
    }
    return s;
}

void expect_stats_eq(const fpp::TableApplyStats& a, const fpp::TableApplyStats& b) {
    EXPECT_EQ(a.phase_valid, b.phase_valid);
    EXPECT_EQ(a.points, b.points);
    EXPECT_EQ(a.no_model, b.no_model);
    EXPECT_EQ(a.out_of_range, b.out_of_range);
}

bool same_bits(const fpp::Image<float>& a, const fpp::Image<float>& b) {
    return a.size() == b.size() && a.channels() == b.channels() &&
           std::memcmp(a.data(), b.data(), a.storage().size() * sizeof(float)) == 0;
}

// Compares every pixel with the double evaluation; returns the largest error (mm).
double check_against_double(const fpp::CoefficientTable& table, const fpp::Image<float>& phase,
                            const fpp::PointCloud& cloud) {
    namespace tp = fpp::table_plane;
    const fpp::TableModel model = table.info().model;
    const bool ray = model != fpp::TableModel::polynomial; // X = xn Z, Y = yn Z
    const bool rational = model == fpp::TableModel::rational;
    const int xn_plane = rational ? tp::rational_xn : tp::ray_xn;
    const int yn_plane = rational ? tp::rational_yn : tp::ray_yn;
    double max_error = 0.0;
    for (int y = 0; y < kSyntheticCamera.height; ++y) {
        for (int x = 0; x < kSyntheticCamera.width; ++x) {
            const float X = cloud.xyz.at(x, y, 0);
            const float Y = cloud.xyz.at(x, y, 1);
            const float Z = cloud.xyz.at(x, y, 2);
            const bool point = kind_of(x, y) == Kind::in_range && synthetic_has_model(x, y);
            if (!point) {
                EXPECT_TRUE(std::isnan(X) && std::isnan(Y) && std::isnan(Z))
                    << "pixel " << x << "," << y << " should have no point";
                continue;
            }
            const double t = (double(phase.at(x, y)) - double(table.get(tp::centre, x, y))) *
                             double(table.get(tp::inv_half_range, x, y));
            float c[3][4];
            for (int k = 0; k < 4; ++k) {
                c[2][k] = table.get((ray ? tp::ray_z : tp::poly_z) + k, x, y);
                if (!ray) {
                    c[0][k] = table.get(tp::poly_x + k, x, y);
                    c[1][k] = table.get(tp::poly_y + k, x, y);
                }
            }
            Horner hz = horner(c[2], t);
            if (rational) {
                // Dividing by 1 + d t (0.85..1.15 here) scales the cubic's
                // error by at most 1.2; the float denominator (two
                // roundings) and the division add 1.5 ulps of |Z|.
                hz.value /= 1 + double(table.get(tp::rational_d, x, y)) * t;
                hz.bound = hz.bound * 1.2 + 1.5 * std::ldexp(1.0, std::ilogb(hz.value) - 23);
            }
            EXPECT_LE(std::fabs(double(Z) - hz.value), hz.bound) << "Z at " << x << "," << y;
            max_error = std::max(max_error, std::fabs(double(Z) - hz.value));
            if (ray) {
                // X = xn Z and Y = yn Z exactly as float products of the kernel's Z.
                EXPECT_EQ(X, table.get(xn_plane, x, y) * Z) << x << "," << y;
                EXPECT_EQ(Y, table.get(yn_plane, x, y) * Z) << x << "," << y;
                const double xd = double(table.get(xn_plane, x, y)) * hz.value;
                max_error = std::max(max_error, std::fabs(double(X) - xd));
            } else {
                const Horner hx = horner(c[0], t);
                const Horner hy = horner(c[1], t);
                const double ex = std::fabs(double(X) - hx.value);
                const double ey = std::fabs(double(Y) - hy.value);
                EXPECT_LE(ex, hx.bound) << "X at " << x << "," << y;
                EXPECT_LE(ey, hy.bound) << "Y at " << x << "," << y;
                max_error = std::max({max_error, ex, ey});
            }
        }
    }
    return max_error;
}

} // namespace

TEST(TableKernel, PolynomialMatchesDoubleEvaluation) {
    const fpp::CoefficientTable table = synthetic_table(fpp::TableModel::polynomial);
    const fpp::Image<float> phase = make_phase();
    fpp::PointCloud cloud;
    fpp::ThreadPool pool(2);
    const fpp::TableApplyStats stats = fpp::apply_table(table, phase, cloud, &pool);
    ASSERT_EQ(cloud.xyz.size(), kSyntheticCamera);
    ASSERT_EQ(cloud.xyz.channels(), 3);
    const double max_error = check_against_double(table, phase, cloud);
    // |Z| < 1024 mm: within 2.5 float ulps (6.1e-5 mm each below 1024 mm).
    EXPECT_LT(max_error, 1.5e-4);
    std::printf("polynomial: max |kernel - double| = %.2e mm\n", max_error);
    expect_stats_eq(stats, expected_stats(table, phase));
    EXPECT_GT(stats.points, 3000u);
    EXPECT_GT(stats.out_of_range, 100u);
    EXPECT_GT(stats.no_model, 50u);
    EXPECT_EQ(stats.points, cloud.count_points());
}

TEST(TableKernel, RayModelGivesXnZAndMatchesDoubleEvaluation) {
    const fpp::CoefficientTable table = synthetic_table(fpp::TableModel::ray);
    const fpp::Image<float> phase = make_phase();
    fpp::PointCloud cloud;
    const fpp::TableApplyStats stats = fpp::apply_table(table, phase, cloud);
    const double max_error = check_against_double(table, phase, cloud);
    EXPECT_LT(max_error, 1.5e-4);
    std::printf("ray: max |kernel - double| = %.2e mm\n", max_error);
    expect_stats_eq(stats, expected_stats(table, phase));
    EXPECT_EQ(stats.points, cloud.count_points());
}

TEST(TableKernel, StatsCountEveryKindOfMissingPoint) {
    // Hand-made: a 16x8 camera in two 8x8 tiles, known pixels.
    fpp::TableInfo info;
    info.camera = {16, 8};
    info.tile_width = 8;
    info.tile_height = 8;
    info.model = fpp::TableModel::ray;
    info.projector = {100, 100};
    fpp::CoefficientTable table(info);
    namespace tp = fpp::table_plane;
    for (int y = 0; y < 8; ++y) {
        for (int x = 0; x < 16; ++x) {
            if (x == 15)
                continue; // column 15: no model
            table.set(tp::centre, x, y, 100.0f);
            table.set(tp::inv_half_range, x, y, 0.5f); // valid for phase 98..102
            table.set(tp::ray_z, x, y, 500.0f);
            table.set(tp::ray_z + 1, x, y, 10.0f);
            table.set(tp::ray_xn, x, y, 0.25f);
            table.set(tp::ray_yn, x, y, -0.5f);
        }
    }
    fpp::Image<float> phase(info.camera, 1, 101.0f);
    // storage().at(): bounds-checked, so GCC sees no null data pointer.
    auto pixel = [&phase](int x, int y) -> float& {
        return phase.storage().at(std::size_t(y * 16 + x));
    };
    pixel(0, 0) = 102.0f;    // t = 1 exactly: a point (the range is closed)
    pixel(1, 0) = 98.0f;     // t = -1 exactly: a point
    pixel(2, 0) = 102.0001f; // just outside
    pixel(3, 0) = 97.0f;     // outside below
    pixel(4, 0) = kNaN;      // not decoded
    pixel(5, 0) = std::numeric_limits<float>::infinity();
    pixel(15, 3) = kNaN; // no model and no phase: only "not decoded"
    fpp::PointCloud cloud;
    cloud.quality = fpp::Image<float>(info.camera, 1, 7.0f);
    const fpp::TableApplyStats s = fpp::apply_table(table, phase, cloud);
    EXPECT_EQ(s.phase_valid, 128u - 3u);
    EXPECT_EQ(s.no_model, 7u);
    EXPECT_EQ(s.out_of_range, 2u);
    EXPECT_EQ(s.points, 128u - 3u - 7u - 2u);
    EXPECT_EQ(cloud.xyz.at(0, 0, 2), 510.0f);
    EXPECT_EQ(cloud.xyz.at(0, 0, 0), 127.5f);
    EXPECT_EQ(cloud.xyz.at(1, 0, 2), 490.0f);
    EXPECT_EQ(cloud.xyz.at(1, 0, 1), -245.0f);
    EXPECT_EQ(cloud.xyz.at(7, 7, 2), 505.0f);
    for (const auto& [x, y] : {std::pair{2, 0}, std::pair{3, 0}, std::pair{4, 0}, std::pair{5, 0},
                               std::pair{15, 0}, std::pair{15, 3}})
        for (int c = 0; c < 3; ++c)
            EXPECT_TRUE(std::isnan(cloud.xyz.at(x, y, c))) << x << "," << y;
    EXPECT_EQ(cloud.quality.at(3, 3), 7.0f); // untouched
}

TEST(TableKernel, SameResultOnOneAndManyThreadsAndAnyTiling) {
    const fpp::Image<float> phase = make_phase();
    for (const fpp::TableModel model : {fpp::TableModel::polynomial, fpp::TableModel::ray}) {
        const fpp::CoefficientTable table = synthetic_table(model);
        fpp::ThreadPool one(1);
        fpp::ThreadPool four(4);
        fpp::PointCloud a, b, c, d;
        const auto sa = fpp::apply_table(table, phase, a, &one);
        const auto sb = fpp::apply_table(table, phase, b, &four);
        const auto sc = fpp::apply_table(table, phase, c); // shared pool
        EXPECT_TRUE(same_bits(a.xyz, b.xyz));
        EXPECT_TRUE(same_bits(a.xyz, c.xyz));
        expect_stats_eq(sa, sb);
        expect_stats_eq(sa, sc);
        // Other tile shapes (one tile across, tall tiles): same points.
        for (const auto& [tw, th] : {std::pair{256, 64}, std::pair{8, 24}}) {
            const fpp::CoefficientTable other = synthetic_table(model, tw, th);
            const auto sd = fpp::apply_table(other, phase, d, &four);
            EXPECT_TRUE(same_bits(a.xyz, d.xyz)) << tw << "x" << th;
            expect_stats_eq(sa, sd);
        }
    }
}

TEST(TableKernel, MappedTableGivesTheSameCloud) {
    const fpp::CoefficientTable table = synthetic_table(fpp::TableModel::polynomial);
    fpp::test::TempDir dir;
    fpp::write_table(dir / "t.fpt", table);
    const fpp::CoefficientTable mapped = fpp::load_table(dir / "t.fpt", &kSyntheticCamera);
    ASSERT_TRUE(mapped.mapped());
    const fpp::Image<float> phase = make_phase();
    fpp::PointCloud a, b;
    fpp::apply_table(table, phase, a);
    fpp::apply_table(mapped, phase, b);
    EXPECT_TRUE(same_bits(a.xyz, b.xyz));
}

TEST(TableKernel, ReusedCloudIsFullyOverwritten) {
    const fpp::CoefficientTable table = synthetic_table(fpp::TableModel::ray);
    const fpp::Image<float> phase = make_phase();
    fpp::PointCloud fresh;
    fpp::apply_table(table, phase, fresh);
    fpp::PointCloud reused;
    reused.xyz = fpp::Image<float>(kSyntheticCamera, 3, 12345.0f);
    fpp::apply_table(table, phase, reused);
    EXPECT_TRUE(same_bits(fresh.xyz, reused.xyz));
    fpp::PointCloud wrong_size;
    wrong_size.xyz = fpp::Image<float>(10, 10, 3, 1.0f);
    fpp::apply_table(table, phase, wrong_size);
    EXPECT_TRUE(same_bits(fresh.xyz, wrong_size.xyz));
}

TEST(TableKernel, BackgroundTilesAreWrittenAsNoPoint) {
    // Phase only in x 40..69, y 10..19 (parts of six 32x8 tiles); every other
    // tile is background and is skipped, yet a reused cloud must come out
    // NaN there and the decoded part identical to a full evaluation.
    const fpp::CoefficientTable table = synthetic_table(fpp::TableModel::rational);
    const fpp::Image<float> full_phase = make_phase();
    fpp::PointCloud full;
    fpp::apply_table(table, full_phase, full);
    fpp::Image<float> phase(kSyntheticCamera, 1, kNaN);
    const auto inside = [](int x, int y) { return x >= 40 && x < 70 && y >= 10 && y < 20; };
    for (int y = 0; y < kSyntheticCamera.height; ++y)
        for (int x = 0; x < kSyntheticCamera.width; ++x)
            if (inside(x, y))
                phase.at(x, y) = full_phase.at(x, y);
    fpp::PointCloud reused;
    reused.xyz = fpp::Image<float>(kSyntheticCamera, 3, 12345.0f);
    const fpp::TableApplyStats stats = fpp::apply_table(table, phase, reused);
    std::size_t points = 0;
    for (int y = 0; y < kSyntheticCamera.height; ++y)
        for (int x = 0; x < kSyntheticCamera.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const float got = reused.xyz.at(x, y, c);
                if (!inside(x, y)) {
                    ASSERT_TRUE(std::isnan(got)) << x << "," << y << "," << c;
                    continue;
                }
                const float want = full.xyz.at(x, y, c);
                ASSERT_TRUE(std::memcmp(&got, &want, sizeof got) == 0) << x << "," << y;
                points += c == 2 && !std::isnan(got) ? 1 : 0;
            }
    EXPECT_GT(points, 200u);
    EXPECT_EQ(stats.points, points);
    expect_stats_eq(stats, expected_stats(table, phase));
}

TEST(TableKernel, RejectsMismatchedInput) {
    const fpp::CoefficientTable table = synthetic_table(fpp::TableModel::ray);
    fpp::PointCloud cloud;
    EXPECT_THROW(fpp::apply_table(table, fpp::Image<float>(99, 37, 1), cloud),
                 std::invalid_argument);
    EXPECT_THROW(fpp::apply_table(table, fpp::Image<float>(100, 38, 1), cloud),
                 std::invalid_argument);
    EXPECT_THROW(fpp::apply_table(table, fpp::Image<float>(100, 37, 2), cloud),
                 std::invalid_argument);
    EXPECT_THROW(fpp::apply_table(table, fpp::Image<float>(), cloud), std::invalid_argument);
    EXPECT_THROW(fpp::apply_table(fpp::CoefficientTable{}, make_phase(), cloud),
                 std::invalid_argument);
}

// The rational model: Z = cubic(t) / (1 + d t), X = xn Z, Y = yn Z.
TEST(TableKernel, RationalModelMatchesDoubleEvaluation) {
    const fpp::CoefficientTable table = synthetic_table(fpp::TableModel::rational);
    const fpp::Image<float> phase = make_phase();
    fpp::PointCloud cloud;
    fpp::ThreadPool pool(2);
    const fpp::TableApplyStats stats = fpp::apply_table(table, phase, cloud, &pool);
    const double max_error = check_against_double(table, phase, cloud);
    // Float Horner plus one division: a few ulps of |Z| < 1100 mm (6.1e-5 mm
    // below 1024, 1.2e-4 mm above).
    std::printf("rational: max |kernel - double| = %.2e mm\n", max_error);
    EXPECT_LT(max_error, 5e-4);
    expect_stats_eq(stats, expected_stats(table, phase));
    EXPECT_GT(stats.points, 3000u);
    EXPECT_EQ(stats.points, cloud.count_points());
}
