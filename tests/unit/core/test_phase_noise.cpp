// The phase-noise model (fpp/phase_noise.hpp) and the predicted sigma_z it
// feeds: the formula against a Monte-Carlo of N-step samples decoded by the
// real decoder (read, shot and rounding noise, 8-bit frames and deeper
// sensors MSB-aligned in 16-bit frames); the kernel's sigma_z against a
// finite difference of the table; sigma_z in the PLY; the filter by sigma_z;
// bad camera noise values refused by name.

#include "fpp/capture_set.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/decoder.hpp"
#include "fpp/parallel.hpp"
#include "fpp/phase_noise.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/table_kernel.hpp"

#include "synthetic_table.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kPi = std::numbers::pi;

// ---------------------------------------------------------------------------
// Monte-Carlo of the formula through the decoder.

// One phase block whose single period spans the projector (decoded
// "direct"), so every camera pixel is an independent trial at its own phase.
struct McCase {
    const char* name;
    int steps;
    double a, b;       // fringe mean and amplitude, sensor DN
    double read, gain; // read noise (sensor DN), electrons per sensor DN (0: no shot noise)
    int sensor_bits;   // 8: 8-bit frames; more: MSB-aligned in 16-bit frames
};

struct McResult {
    double rms_normalised = 0; // RMS of (decoded - true) / predicted sigma
    double rms_error_px = 0;
    double mean_sigma_px = 0;
    std::size_t trials = 0;
};

constexpr fpp::Size kMcCamera{256, 200};
constexpr int kMcProjector = 256;

fpp::Sequence mc_sequence(int steps) {
    return {fpp::PhaseBlock{fpp::Axis::x, double(kMcProjector), steps, 1, 0.0}};
}

// Frames of I_k = a + b cos(2 pi p / period + 2 pi k / N) plus Gaussian
// noise of variance read^2 + I / gain (sensor DN), rounded and clipped at
// the sensor's depth, shifted into 16-bit frames above 8 bits. Truth p
// uniform in [20, 236] (away from the wrap of the single period).
fpp::CaptureSet mc_capture(const McCase& c, std::vector<double>& truth, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> uniform(20.0, kMcProjector - 20.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    const std::size_t n = std::size_t(kMcCamera.width) * std::size_t(kMcCamera.height);
    truth.resize(n);
    for (double& p : truth)
        p = uniform(rng);
    fpp::CaptureSet set;
    set.manifest.camera = kMcCamera;
    set.manifest.projector = {kMcProjector, 16};
    set.manifest.sequence = mc_sequence(c.steps);
    const double full = std::ldexp(1.0, c.sensor_bits) - 1.0;
    const int shift = c.sensor_bits > 8 ? 16 - c.sensor_bits : 0;
    for (int k = 0; k < c.steps; ++k) {
        fpp::Frame f;
        f.bit_depth = c.sensor_bits > 8 ? 16 : 8;
        if (f.bit_depth == 8)
            f.u8 = fpp::Image<std::uint8_t>(kMcCamera);
        else
            f.u16 = fpp::Image<std::uint16_t>(kMcCamera);
        for (std::size_t i = 0; i < n; ++i) {
            const double ideal =
                c.a + c.b * std::cos(2 * kPi * truth[i] / kMcProjector + 2 * kPi * k / c.steps);
            const double var = c.read * c.read + (c.gain > 0 ? std::max(ideal, 0.0) / c.gain : 0);
            const double v = std::clamp(std::round(ideal + std::sqrt(var) * gauss(rng)), 0.0, full);
            if (f.bit_depth == 8)
                f.u8.data()[i] = static_cast<std::uint8_t>(v);
            else
                f.u16.data()[i] = static_cast<std::uint16_t>(static_cast<unsigned>(v) << shift);
        }
        set.manifest.frames.push_back(std::to_string(k) + ".png");
        set.frames.push_back(std::move(f));
    }
    return set;
}

McResult run_mc(const McCase& c, const fpp::CameraNoise& camera, std::uint32_t seed) {
    std::vector<double> truth;
    const fpp::CaptureSet set = mc_capture(c, truth, seed);
    const fpp::DecodeResult r = fpp::decode(set);
    const int frame_bits = c.sensor_bits > 8 ? 16 : 8;
    const fpp::PhaseNoiseModel model =
        fpp::phase_noise_model(set.manifest.sequence, fpp::Axis::x, camera, frame_bits);
    fpp::Image<float> sigma;
    fpp::coordinate_sigma(r.modulation, r.mean, model, sigma);
    McResult m;
    double sum_r2 = 0, sum_e2 = 0, sum_s = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
        if (!(r.mask.data()[i] & fpp::kDecodeValid))
            continue;
        const double e = double(r.proj_x.data()[i]) - truth[i];
        const double s = double(sigma.data()[i]);
        sum_r2 += (e / s) * (e / s);
        sum_e2 += e * e;
        sum_s += s;
        ++m.trials;
    }
    if (m.trials > 0) {
        const auto n = double(m.trials);
        m.rms_normalised = std::sqrt(sum_r2 / n);
        m.rms_error_px = std::sqrt(sum_e2 / n);
        m.mean_sigma_px = sum_s / n;
    }
    return m;
}

fpp::CameraNoise noise_of(const McCase& c) {
    return fpp::CameraNoise{c.read, c.gain, c.sensor_bits};
}

// 51200 trials each: the RMS ratio's own statistical spread is 0.3 %.
// The dark case (B = 8 DN, 1.2 DN of noise) checks the correction of B^2
// for the noise's share: without it, it reads 1.007.
TEST(PhaseNoise, FormulaMatchesMonteCarloThroughTheDecoder) {
    const McCase cases[] = {
        {"8-bit N=4 bright, read + shot", 4, 120, 90, 1.0, 40, 8},
        {"8-bit N=8 dark, read + shot", 8, 12, 8, 1.0, 40, 8},
        {"8-bit N=3, read only", 3, 80, 60, 1.5, 0, 8},
        {"8-bit N=8, rounding a third of the noise", 8, 100, 60, 0.5, 0, 8},
        {"12-bit sensor in 16-bit frames N=4", 4, 1500, 1000, 2.0, 5, 12},
        {"10-bit sensor in 16-bit frames N=6", 6, 300, 200, 1.2, 2, 10},
    };
    std::uint32_t seed = 11;
    for (const McCase& c : cases) {
        SCOPED_TRACE(c.name);
        const McResult m = run_mc(c, noise_of(c), seed++);
        std::printf("[ figures  ] %-42s trials %zu: rms error %.5f px, mean predicted sigma "
                    "%.5f px, rms(error / sigma) %.4f\n",
                    c.name, m.trials, m.rms_error_px, m.mean_sigma_px, m.rms_normalised);
        EXPECT_EQ(m.trials, std::size_t(kMcCamera.width) * std::size_t(kMcCamera.height));
        EXPECT_GT(m.rms_normalised, 0.98);
        EXPECT_LT(m.rms_normalised, 1.02);
    }
}

TEST(PhaseNoise, RoundingTermIsNeeded) {
    // Read noise 0.5 DN: rounding adds a third of the variance. Without the
    // q^2/12 term the model would predict 0.87 of the noise; check that the
    // Monte-Carlo sees that difference (so the test above could fail).
    const McCase c{"rounding", 8, 100, 60, 0.5, 0, 8};
    const McResult m = run_mc(c, noise_of(c), 5);
    fpp::PhaseNoiseModel model =
        fpp::phase_noise_model(mc_sequence(8), fpp::Axis::x, noise_of(c), 8);
    const double with = fpp::sample_variance_dn2(model, 100.0);
    const double without = with - 1.0 / 12.0;
    const double ratio_without = m.rms_normalised * std::sqrt(with / without);
    std::printf("[ figures  ] rms(error / sigma) %.4f with the rounding term, %.4f without\n",
                m.rms_normalised, ratio_without);
    EXPECT_GT(ratio_without, 1.1);
}

TEST(PhaseNoise, DeeperSensorsAreConvertedToFrameDn) {
    // 12-bit sensor, frames MSB-aligned in 16 bits: s = 16 frame DN per
    // sensor DN. read 2 DN -> 32 frame DN; A = 16000 frame DN = 1000 sensor
    // DN, gain 10 e-/DN: 100 sensor DN^2 of shot noise = 25600 frame DN^2;
    // rounding at 16 frame DN: 256 / 12.
    fpp::PhaseNoiseModel model;
    model.camera = {2.0, 10.0, 12};
    model.frame_bit_depth = 16;
    model.steps = 4;
    model.period = 20;
    EXPECT_NEAR(fpp::sample_variance_dn2(model, 16000.0), 32.0 * 32.0 + 25600.0 + 256.0 / 12.0,
                1e-9);
    // The same sensor delivering 8-bit frames (its top 8 bits): s = 1/16,
    // rounding at the frame's 1 DN.
    model.frame_bit_depth = 8;
    EXPECT_NEAR(fpp::sample_variance_dn2(model, 62.5),
                (2.0 / 16) * (2.0 / 16) + 62.5 / 16 / 10 + 1.0 / 12.0, 1e-12);
    // 8-bit sensor, 8-bit frames.
    model.camera = {1.0, 40.0, 8};
    EXPECT_NEAR(fpp::sample_variance_dn2(model, 100.0), 1.0 + 2.5 + 1.0 / 12.0, 1e-12);

    // coordinate_sigma: sqrt(2 var / (N B_s^2)) period / (2 pi) with
    // B_s^2 = max(B^2 - 4 var / N, B^2 / 2); B <= 0, not finite or A NaN
    // give NaN; A < 0 counts as 0.
    model.camera = {2.0, 10.0, 12};
    model.frame_bit_depth = 16;
    fpp::Image<float> b(6, 1, 1, 8000.0f), a(6, 1, 1, 16000.0f), out;
    b.at(1, 0) = 0.0f;
    b.at(2, 0) = std::numeric_limits<float>::infinity();
    a.at(3, 0) = kNaN;
    a.at(4, 0) = -50.0f;
    b.at(5, 0) = 200.0f; // B^2 = 40000 < 8 var / N: B_s^2 = B^2 / 2
    fpp::coordinate_sigma(b, a, model, out);
    ASSERT_EQ(out.size(), b.size());
    const auto predicted = [&](double bb, double aa) {
        const double var = fpp::sample_variance_dn2(model, aa);
        const double signal2 = std::max(bb * bb - 4 * var / 4, bb * bb / 2);
        return std::sqrt(2 * var / (4 * signal2)) * 20 / (2 * kPi);
    };
    EXPECT_NEAR(out.at(0, 0), predicted(8000, 16000), 3e-5 * predicted(8000, 16000));
    // The noise's share of B^2 (4 var / N) is 4e-4 of it here: visible.
    const double uncorrected =
        std::sqrt(2 * fpp::sample_variance_dn2(model, 16000) / (4 * 8000.0 * 8000.0)) * 20 /
        (2 * kPi);
    EXPECT_GT(std::fabs(double(out.at(0, 0)) - uncorrected), 1e-4 * uncorrected);
    EXPECT_TRUE(std::isnan(out.at(1, 0)));
    EXPECT_TRUE(std::isnan(out.at(2, 0)));
    EXPECT_TRUE(std::isnan(out.at(3, 0)));
    EXPECT_NEAR(out.at(4, 0), predicted(8000, 0), 3e-5 * predicted(8000, 0));
    EXPECT_NEAR(out.at(5, 0), predicted(200, 16000), 3e-5 * predicted(200, 16000));
    // `out` of the right size is reused (no allocation).
    const float* before = out.data();
    fpp::coordinate_sigma(b, a, model, out);
    EXPECT_EQ(out.data(), before);

    // Monte-Carlo: predicting a 12-bit sensor as if it were 16-bit (read
    // noise in frame DN 16 times too small) is far off, so the conversion
    // is what the first test checks.
    const McCase c{"12-bit", 4, 1500, 1000, 2.0, 5, 12};
    const McResult right = run_mc(c, noise_of(c), 21);
    const McResult wrong = run_mc(c, fpp::CameraNoise{2.0, 5.0, 16}, 21);
    std::printf("[ figures  ] 12-bit in 16-bit frames: rms(error / sigma) %.4f converted, "
                "%.4f taken as a 16-bit sensor\n",
                right.rms_normalised, wrong.rms_normalised);
    EXPECT_NEAR(right.rms_normalised, 1.0, 0.03);
    EXPECT_GT(wrong.rms_normalised, 2.0);
}

TEST(PhaseNoise, ModelTakesTheFinestPhaseBlockOfTheAxis) {
    const fpp::Sequence seq = {
        fpp::WhiteBlock{},
        fpp::PhaseBlock{fpp::Axis::x, 160.0, 4, 1, 0.0},
        fpp::PhaseBlock{fpp::Axis::x, 20.0, 8, 1, 0.0},
        fpp::PhaseBlock{fpp::Axis::y, 18.0, 5, 1, 0.0},
    };
    const fpp::CameraNoise camera{1.0, 40.0, 8};
    const fpp::PhaseNoiseModel x = fpp::phase_noise_model(seq, fpp::Axis::x, camera, 8);
    EXPECT_EQ(x.steps, 8);
    EXPECT_EQ(x.period, 20.0);
    EXPECT_EQ(x.frame_bit_depth, 8);
    EXPECT_EQ(x.camera.gain_e_per_dn, 40.0);
    const fpp::PhaseNoiseModel y = fpp::phase_noise_model(seq, fpp::Axis::y, camera, 16);
    EXPECT_EQ(y.steps, 5);
    EXPECT_EQ(y.period, 18.0);
    const fpp::Sequence only_x = {fpp::PhaseBlock{fpp::Axis::x, 20.0, 8, 1, 0.0}};
    EXPECT_THROW(fpp::phase_noise_model(only_x, fpp::Axis::y, camera, 8), std::invalid_argument);
}

// The message of the std::invalid_argument thrown by f, "" if none.
template <class F> std::string invalid_argument_message(F&& f) {
    try {
        f();
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "";
}

TEST(PhaseNoise, BadCameraNoiseIsRefusedNamingTheField) {
    const double inf = std::numeric_limits<double>::infinity();
    const struct {
        fpp::CameraNoise noise;
        const char* field;
    } bad[] = {
        {{-0.5, 40.0, 8}, "read_noise_dn"},        {{std::nan(""), 40.0, 8}, "read_noise_dn"},
        {{inf, 40.0, 8}, "read_noise_dn"},         {{1.0, -1.0, 8}, "gain_e_per_dn"},
        {{1.0, std::nan(""), 8}, "gain_e_per_dn"}, {{1.0, inf, 8}, "gain_e_per_dn"},
        {{1.0, 40.0, 7}, "sensor_bit_depth"},      {{1.0, 40.0, 17}, "sensor_bit_depth"},
    };
    for (const auto& b : bad) {
        const std::string what = invalid_argument_message([&] { b.noise.validate(); });
        EXPECT_NE(what.find(b.field), std::string::npos) << "'" << what << "'";
        const std::string from_model = invalid_argument_message(
            [&] { fpp::phase_noise_model(mc_sequence(4), fpp::Axis::x, b.noise, 8); });
        EXPECT_NE(from_model.find(b.field), std::string::npos) << "'" << from_model << "'";
    }
    EXPECT_NO_THROW((fpp::CameraNoise{0.0, 0.0, 16}.validate()));
    EXPECT_NO_THROW((fpp::CameraNoise{1.0, 40.0, 8}.validate()));
    const std::string depth = invalid_argument_message([] {
        fpp::phase_noise_model(mc_sequence(4), fpp::Axis::x, fpp::CameraNoise{1.0, 40.0, 12}, 12);
    });
    EXPECT_NE(depth.find("frame_bit_depth"), std::string::npos) << depth;
    fpp::Image<float> b(4, 4, 1, 10.0f), a(4, 4, 1, 50.0f), small(3, 4, 1, 50.0f), out;
    fpp::PhaseNoiseModel model;
    model.camera = {1.0, 40.0, 8};
    model.steps = 2;
    model.period = 20;
    EXPECT_NE(
        invalid_argument_message([&] { fpp::coordinate_sigma(b, a, model, out); }).find("steps"),
        std::string::npos);
    model.steps = 4;
    EXPECT_THROW(fpp::coordinate_sigma(b, small, model, out), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// The kernel's sigma_z against a finite difference of the table.

using fpp::test::kSyntheticCamera;
using fpp::test::synthetic_has_model;
using fpp::test::synthetic_pixel;
using fpp::test::synthetic_table;

// In range, except NaN, out of range, and a band of rows without any phase
// (whole background tiles at rows 16..23).
fpp::Image<float> make_phase() {
    fpp::Image<float> phase(kSyntheticCamera, 1);
    for (int y = 0; y < kSyntheticCamera.height; ++y)
        for (int x = 0; x < kSyntheticCamera.width; ++x) {
            const fpp::test::SyntheticPixel p = synthetic_pixel(x, y);
            const double s = std::sin(0.37 * x + 0.11 * y);
            const double half = 1.0 / p.ihr;
            const int k = (x * 13 + y * 5) % 41;
            float v = float(p.centre + 0.97 * s * half);
            if (k == 0 || (y >= 16 && y < 24))
                v = kNaN;
            else if (k == 2)
                v = float(p.centre + 1.3 * half);
            phase.at(x, y) = v;
        }
    return phase;
}

// Coordinate sigma 0.01 .. 0.2 px, NaN at a few decoded pixels.
fpp::Image<float> make_sigma() {
    fpp::Image<float> sigma(kSyntheticCamera, 1);
    for (int y = 0; y < kSyntheticCamera.height; ++y)
        for (int x = 0; x < kSyntheticCamera.width; ++x)
            sigma.at(x, y) = (x + y) % 37 == 5
                                 ? kNaN
                                 : float(0.01 + 0.19 * (0.5 + 0.5 * std::cos(0.21 * x - 0.3 * y)));
    return sigma;
}

// Z of pixel (x, y) at projector coordinate p, in double from the table's
// float coefficients.
double z_at(const fpp::CoefficientTable& table, int x, int y, double p) {
    namespace tp = fpp::table_plane;
    const fpp::TableModel model = table.info().model;
    const double t =
        (p - double(table.get(tp::centre, x, y))) * double(table.get(tp::inv_half_range, x, y));
    const int zp = model == fpp::TableModel::polynomial ? tp::poly_z : tp::ray_z;
    double z = 0;
    for (int k = 3; k >= 0; --k)
        z = z * t + double(table.get(zp + k, x, y));
    if (model == fpp::TableModel::rational)
        z /= 1.0 + double(table.get(tp::rational_d, x, y)) * t;
    return z;
}

// The size of the terms the kernel's dZ/dp sums (mm per projector px), which
// sets its float rounding error: (sum_k k |c_k| |t|^(k-1) + |Z d|) /
// |1 + d t| * inv_half_range (d = 0 but for the rational model). Where the
// two terms of the rational model's quotient rule nearly cancel, dZ/dp is
// small against them and only its absolute error is small.
double slope_terms(const fpp::CoefficientTable& table, int x, int y, double p) {
    namespace tp = fpp::table_plane;
    const fpp::TableModel model = table.info().model;
    const double ihr = double(table.get(tp::inv_half_range, x, y));
    const double t = (p - double(table.get(tp::centre, x, y))) * ihr;
    const int zp = model == fpp::TableModel::polynomial ? tp::poly_z : tp::ray_z;
    double terms = 0;
    for (int k = 1; k <= 3; ++k)
        terms += k * std::fabs(double(table.get(zp + k, x, y))) * std::pow(std::fabs(t), k - 1);
    double d = 0;
    if (model == fpp::TableModel::rational)
        d = double(table.get(tp::rational_d, x, y));
    return (terms + std::fabs(z_at(table, x, y, p) * d)) / std::fabs(1 + d * t) * ihr;
}

bool same_bits(const fpp::Image<float>& a, const fpp::Image<float>& b) {
    return a.size() == b.size() && a.channels() == b.channels() &&
           std::memcmp(a.data(), b.data(), a.storage().size() * sizeof(float)) == 0;
}

TEST(PhaseNoise, KernelSigmaZMatchesFiniteDifferenceOfTheTable) {
    const fpp::Image<float> phase = make_phase();
    const fpp::Image<float> sigma = make_sigma();
    for (const fpp::TableModel model :
         {fpp::TableModel::polynomial, fpp::TableModel::ray, fpp::TableModel::rational}) {
        SCOPED_TRACE(fpp::to_string(model));
        const fpp::CoefficientTable table = synthetic_table(model);
        fpp::PointCloud with, without;
        // A reused cloud with stale values everywhere.
        with.xyz = fpp::Image<float>(kSyntheticCamera, 3, 1.0f);
        with.sigma_z = fpp::Image<float>(kSyntheticCamera, 1, 1.0f);
        fpp::ThreadPool pool(2);
        const fpp::TableApplyStats s1 = fpp::apply_table(table, phase, with, &pool, &sigma);
        const fpp::TableApplyStats s2 = fpp::apply_table(table, phase, without, &pool);
        // Points, counts and coordinates do not change with sigma.
        EXPECT_TRUE(same_bits(with.xyz, without.xyz));
        EXPECT_EQ(s1.points, s2.points);
        EXPECT_TRUE(without.sigma_z.empty());
        ASSERT_EQ(with.sigma_z.size(), kSyntheticCamera);
        ASSERT_EQ(with.sigma_z.channels(), 1);

        double worst = 0, worst_rel = 0;
        std::size_t compared = 0, unknown = 0;
        for (int y = 0; y < kSyntheticCamera.height; ++y)
            for (int x = 0; x < kSyntheticCamera.width; ++x) {
                const float sz = with.sigma_z.at(x, y);
                if (!std::isfinite(with.xyz.at(x, y, 2))) {
                    EXPECT_TRUE(std::isnan(sz)) << x << "," << y;
                    continue;
                }
                if (std::isnan(sigma.at(x, y))) {
                    EXPECT_TRUE(std::isnan(sz)) << x << "," << y;
                    ++unknown;
                    continue;
                }
                // Central difference over +-0.01 px (truncation ~1e-10 of
                // the slope for these cubics).
                const double p = double(phase.at(x, y)), h = 0.01;
                const double slope =
                    (z_at(table, x, y, p + h) - z_at(table, x, y, p - h)) / (2 * h);
                const double expected = std::fabs(slope) * double(sigma.at(x, y));
                const double error = std::fabs(double(sz) - expected);
                worst_rel = std::max(worst_rel, error / expected);
                worst =
                    std::max(worst, error / (slope_terms(table, x, y, p) * double(sigma.at(x, y))));
                ++compared;
            }
        std::printf("[ figures  ] %-10s sigma_z vs finite difference: %zu points, worst "
                    "difference %.2e of the slope's terms (%.2e of sigma_z), %zu with unknown "
                    "coordinate sigma\n",
                    fpp::to_string(model), compared, worst, worst_rel, unknown);
        EXPECT_GT(compared, 2000u);
        EXPECT_GT(unknown, 20u);
        // A few float roundings of the terms (6e-8 each).
        EXPECT_LT(worst, 1e-6);
    }
}

TEST(PhaseNoise, KernelSigmaZIsTheSameOnAnyThreadsAndTiling) {
    const fpp::Image<float> phase = make_phase();
    const fpp::Image<float> sigma = make_sigma();
    for (const fpp::TableModel model : {fpp::TableModel::ray, fpp::TableModel::rational}) {
        fpp::ThreadPool one(1), four(4);
        fpp::PointCloud a, b, c;
        fpp::apply_table(synthetic_table(model), phase, a, &one, &sigma);
        fpp::apply_table(synthetic_table(model), phase, b, &four, &sigma);
        fpp::apply_table(synthetic_table(model, 8, 24), phase, c, &four, &sigma);
        EXPECT_TRUE(same_bits(a.sigma_z, b.sigma_z));
        EXPECT_TRUE(same_bits(a.sigma_z, c.sigma_z));
    }
    // A sigma image of another size is refused; a later call without sigma
    // leaves the cloud's sigma_z empty.
    fpp::PointCloud cloud;
    const fpp::Image<float> wrong(kSyntheticCamera.width, kSyntheticCamera.height + 1, 1, 0.1f);
    EXPECT_THROW(
        fpp::apply_table(synthetic_table(fpp::TableModel::ray), phase, cloud, nullptr, &wrong),
        std::invalid_argument);
    fpp::apply_table(synthetic_table(fpp::TableModel::ray), phase, cloud, nullptr, &sigma);
    EXPECT_FALSE(cloud.sigma_z.empty());
    fpp::apply_table(synthetic_table(fpp::TableModel::ray), phase, cloud);
    EXPECT_TRUE(cloud.sigma_z.empty());
}

// ---------------------------------------------------------------------------
// sigma_z in the PLY and the filter.

fpp::PointCloud small_cloud(bool with_sigma) {
    fpp::PointCloud c;
    c.xyz = fpp::Image<float>(7, 5, 3, kNaN);
    c.quality = fpp::Image<float>(7, 5, 1, 20.0f);
    c.intensity = fpp::Image<float>(7, 5, 1, 90.0f);
    if (with_sigma)
        c.sigma_z = fpp::Image<float>(7, 5, 1, kNaN);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 7; ++x) {
            if ((x + 2 * y) % 4 == 1)
                continue;
            c.xyz.at(x, y, 0) = float(x) * 1.5f;
            c.xyz.at(x, y, 1) = float(y) * -2.25f;
            c.xyz.at(x, y, 2) = 480.0f + float(x + y) / 3.0f;
            if (with_sigma)
                c.sigma_z.at(x, y) = 0.001f + 0.0137f * float(x * 5 + y);
        }
    return c;
}

TEST(PhaseNoise, PlyRoundTripWithSigmaZ) {
    const fpp::test::TempDir dir;
    const fpp::PointCloud cloud = small_cloud(true);
    fpp::write_ply(dir / "s.ply", cloud, {"sigma test"});
    const std::string bytes = fpp::encode_ply(cloud, {"sigma test"});
    EXPECT_NE(bytes.find("property float intensity\nproperty float sigma_z\nproperty uint pixel\n"),
              std::string::npos);
    const std::size_t header = bytes.find("end_header\n") + 11;
    EXPECT_EQ(bytes.size() - header, cloud.count_points() * 28);
    // write_ply_synced (pieces, on a thread) writes the same bytes.
    fpp::write_ply_synced(dir / "synced.ply", cloud, {"sigma test"});
    EXPECT_EQ(fpp::read_ply(dir / "synced.ply").sigma_z, fpp::read_ply(dir / "s.ply").sigma_z);

    const fpp::PlyPoints back = fpp::read_ply(dir / "s.ply");
    ASSERT_EQ(back.size(), cloud.count_points());
    ASSERT_EQ(back.sigma_z.size(), back.size());
    ASSERT_EQ(back.pixel.size(), back.size());
    for (std::size_t i = 0; i < back.size(); ++i) {
        const std::uint32_t p = back.pixel[i];
        EXPECT_EQ(back.sigma_z[i], cloud.sigma_z.data()[p]);
        EXPECT_EQ(back.z[i], cloud.xyz.data()[3 * std::size_t(p) + 2]);
        EXPECT_EQ(back.quality[i], 20.0f);
        EXPECT_EQ(back.intensity[i], 90.0f);
    }
    // Without sigma_z: no property, 24-byte records, nothing read back.
    const fpp::PointCloud plain = small_cloud(false);
    const std::string plain_bytes = fpp::encode_ply(plain);
    EXPECT_EQ(plain_bytes.find("sigma_z"), std::string::npos);
    fpp::write_ply(dir / "p.ply", plain);
    EXPECT_TRUE(fpp::read_ply(dir / "p.ply").sigma_z.empty());
    // A sigma_z of another size is refused.
    fpp::PointCloud bad = small_cloud(true);
    bad.sigma_z = fpp::Image<float>(6, 5, 1, 0.1f);
    EXPECT_THROW(fpp::encode_ply(bad), std::invalid_argument);
}

TEST(PhaseNoise, DropPointsAboveSigma) {
    fpp::PointCloud cloud = small_cloud(true);
    const std::size_t before = cloud.count_points();
    const float limit = 0.2f;
    std::size_t above = 0;
    for (std::size_t i = 0; i < cloud.sigma_z.pixel_count(); ++i)
        above += cloud.sigma_z.data()[i] > limit ? 1 : 0;
    // Unknown sigma (0.056 mm before) on a point: kept.
    ASSERT_TRUE(std::isfinite(cloud.xyz.at(0, 4, 2)));
    cloud.sigma_z.at(0, 4) = kNaN;
    const std::size_t dropped = fpp::drop_points_above_sigma(cloud, limit);
    EXPECT_EQ(dropped, above);
    EXPECT_GT(dropped, 5u);
    EXPECT_EQ(cloud.count_points(), before - dropped);
    for (std::size_t i = 0; i < cloud.sigma_z.pixel_count(); ++i)
        if (std::isfinite(cloud.xyz.data()[3 * i + 2])) {
            EXPECT_FALSE(cloud.sigma_z.data()[i] > limit);
        }
    EXPECT_EQ(fpp::drop_points_above_sigma(cloud, limit), 0u);
    fpp::PointCloud no_sigma = small_cloud(false);
    EXPECT_THROW(fpp::drop_points_above_sigma(no_sigma, limit), std::invalid_argument);
    EXPECT_THROW(fpp::drop_points_above_sigma(cloud, 0.0f), std::invalid_argument);
    EXPECT_THROW(fpp::drop_points_above_sigma(cloud, kNaN), std::invalid_argument);
}

} // namespace
