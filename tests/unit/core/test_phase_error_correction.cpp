// The data-only phase-error correction (fpp/phase_error_correction.hpp) on
// synthetic coordinate maps whose error is known: the decoded coordinate of
// an N-step block under a projector gamma, computed analytically; an odd
// error put in by hand; a linear response; too few pixels or fringes; an
// aliased fronto-parallel sampling; the seam at u = 0 / 1; and the decoder
// option (batch and streaming, frames synthesised from the same model).

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/parallel.hpp"
#include "fpp/phase_error_correction.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

constexpr double kPi = std::numbers::pi;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

fpp::PhaseBlock block(int steps, double period, int shift_sign = 1, double offset = 0) {
    fpp::PhaseBlock b;
    b.axis = fpp::Axis::x;
    b.period = period;
    b.steps = steps;
    b.shift_sign = shift_sign;
    b.phase_offset = offset;
    return b;
}

// A smooth, non-fronto-parallel map from camera pixel to projector column
// (projector pixels): a perspective-like stretch, so the fringe spacing in
// camera pixels varies over the image (about 2.6 to 3.6 projector pixels per
// camera pixel at 320 x 240).
double true_column(int x, int y) {
    const double u = x / 320.0, v = y / 240.0;
    return 40.0 + 800.0 * u / (1.0 + 0.35 * u) + 90.0 * v + 25.0 * u * v;
}

// The coordinate the decoder reports for true coordinate p when the
// projector emits response(level) of the drive level (levels in [0, 1]):
// the N-step phase of the captured samples, unwrapped next to p.
double decoded_column(double p, const fpp::PhaseBlock& b,
                      const std::function<double(double)>& response) {
    const double theta = 2 * kPi * p / b.period + b.phase_offset;
    double c = 0, s = 0;
    for (int k = 0; k < b.steps; ++k) {
        const double delta = 2 * kPi * k / b.steps;
        const double sample = response(0.5 + 0.5 * std::cos(theta + b.shift_sign * delta));
        c += std::cos(delta) * sample;
        s += -b.shift_sign * std::sin(delta) * sample;
    }
    const double error = std::remainder(std::atan2(s, c) - theta, 2 * kPi);
    return p + error * b.period / (2 * kPi);
}

double gamma22(double level) {
    return std::pow(level, 2.2) + 0.005;
}
double linear(double level) {
    return level;
}

struct Maps {
    fpp::Image<float> truth;
    fpp::Image<float> decoded;
    fpp::Image<std::uint8_t> mask;
};

Maps make_maps(const fpp::PhaseBlock& b, const std::function<double(double)>& response,
               int width = 320, int height = 240) {
    Maps m{fpp::Image<float>(width, height), fpp::Image<float>(width, height),
           fpp::Image<std::uint8_t>(width, height, 1, fpp::kDecodeValid)};
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const double p = true_column(x, y);
            m.truth.at(x, y) = static_cast<float>(p);
            m.decoded.at(x, y) = static_cast<float>(decoded_column(p, b, response));
        }
    return m;
}

double rms_error(const fpp::Image<float>& a, const fpp::Image<float>& truth) {
    double s = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.pixel_count(); ++i) {
        if (!std::isfinite(a.data()[i]))
            continue;
        const double e = double(a.data()[i]) - double(truth.data()[i]);
        s += e * e;
        ++n;
    }
    return std::sqrt(s / static_cast<double>(n));
}

TEST(PhaseErrorCorrection, RemovesTheErrorOfGamma22With3And4Steps) {
    // Without blur or noise, the error is the textbook one: with 3 steps,
    // 0.65 px RMS at period 20 (gamma 2.2); 8 sine terms leave 0.3 % of it.
    for (const int steps : {3, 4}) {
        for (const int sign : {1, -1}) {
            const fpp::PhaseBlock b = block(steps, 20.0, sign, 0.3);
            Maps m = make_maps(b, gamma22);
            const double before = rms_error(m.decoded, m.truth);
            const fpp::PhaseErrorSummary s = fpp::correct_phase_error(m.decoded, m.mask, b);
            const double after = rms_error(m.decoded, m.truth);
            std::printf("[ figures  ] %d steps, shift sign %+d: RMS error %.4f -> %.5f px; %s\n",
                        steps, sign, before, after, fpp::describe(s).c_str());
            ASSERT_TRUE(s.applied) << s.reason;
            EXPECT_GT(s.sub_periods, 100);
            EXPECT_NEAR(s.rms_px, before, 0.05 * before);
            if (steps == 3) {
                EXPECT_GT(before, 0.6);
                EXPECT_LT(after, 0.01);
            } else {
                EXPECT_GT(before, 0.02);
                EXPECT_LT(after, 0.002);
            }
        }
    }
}

TEST(PhaseErrorCorrection, RecoversAnOddErrorWithItsSign) {
    // Decoded fold u_m = u + A sin(2 pi u): the correction is c(u) ~ -A sin(2 pi u).
    const fpp::PhaseBlock b = block(4, 24.0);
    const double unit = b.period / b.steps;
    for (const double amplitude : {0.02, -0.03}) {
        Maps m = make_maps(b, linear);
        for (std::size_t i = 0; i < m.truth.pixel_count(); ++i) {
            const double p = m.truth.data()[i];
            const double u = fpp::phase_error_fold(b, p);
            m.decoded.data()[i] = static_cast<float>(p + unit * amplitude * std::sin(2 * kPi * u));
        }
        const fpp::PhaseErrorSummary s = fpp::correct_phase_error(m.decoded, m.mask, b);
        std::printf("[ figures  ] A = %+.3f: b1 = %+.5f, b2 = %+.5f; residual %.5f px\n", amplitude,
                    s.sine[0], s.sine[1], rms_error(m.decoded, m.truth));
        ASSERT_TRUE(s.applied) << s.reason;
        EXPECT_NEAR(s.sine[0], -amplitude, 0.05 * std::abs(amplitude));
        EXPECT_LT(rms_error(m.decoded, m.truth), 0.01 * std::abs(amplitude) * unit);
    }
}

TEST(PhaseErrorCorrection, LeavesALinearResponseAlone) {
    for (const int steps : {3, 8}) {
        const fpp::PhaseBlock b = block(steps, 20.0);
        Maps m = make_maps(b, linear);
        // Noise as a camera gives it: 0.05 px.
        std::mt19937 rng(7);
        std::normal_distribution<float> noise(0.0f, 0.05f);
        for (std::size_t i = 0; i < m.decoded.pixel_count(); ++i)
            m.decoded.data()[i] += noise(rng);
        const fpp::Image<float> before = m.decoded;
        const fpp::PhaseErrorSummary s = fpp::correct_phase_error(m.decoded, m.mask, b);
        double largest = 0;
        for (std::size_t i = 0; i < before.pixel_count(); ++i)
            largest =
                std::max(largest, std::abs(double(m.decoded.data()[i]) - double(before.data()[i])));
        std::printf("[ figures  ] linear, %d steps: %s; largest change %.5f px\n", steps,
                    fpp::describe(s).c_str(), largest);
        EXPECT_LT(s.rms_px, 0.002);
        EXPECT_LT(largest, 0.005);
    }
}

TEST(PhaseErrorCorrection, TooFewPixelsOrFringesLeaveTheCoordinatesUnchanged) {
    const fpp::PhaseBlock b = block(3, 20.0);
    {
        Maps m = make_maps(b, gamma22);
        std::fill(m.mask.storage().begin(), m.mask.storage().end(), std::uint8_t{0});
        for (int y = 0; y < 40; ++y)
            for (int x = 0; x < 40; ++x)
                m.mask.at(x, y) = fpp::kDecodeValid; // 1600 < 4000 pixels
        const fpp::Image<float> before = m.decoded;
        const fpp::PhaseErrorSummary s = fpp::correct_phase_error(m.decoded, m.mask, b);
        EXPECT_TRUE(s.attempted);
        EXPECT_FALSE(s.applied);
        EXPECT_NE(s.reason.find("too few valid pixels"), std::string::npos) << s.reason;
        EXPECT_EQ(
            0, std::memcmp(before.data(), m.decoded.data(), before.pixel_count() * sizeof(float)));
    }
    {
        // Plenty of pixels on a strip two fringes wide: 6 sub-periods.
        Maps m = make_maps(b, gamma22);
        for (int y = 0; y < m.mask.height(); ++y)
            for (int x = 0; x < m.mask.width(); ++x) {
                const double p = m.truth.at(x, y);
                m.mask.at(x, y) = (p >= 300 && p < 340) ? fpp::kDecodeValid : 0;
            }
        const fpp::Image<float> before = m.decoded;
        const fpp::PhaseErrorSummary s = fpp::correct_phase_error(m.decoded, m.mask, b);
        std::printf("[ figures  ] strip of two fringes: %s\n", fpp::describe(s).c_str());
        EXPECT_FALSE(s.applied);
        EXPECT_NE(s.reason.find("too few sub-periods"), std::string::npos) << s.reason;
        EXPECT_EQ(
            0, std::memcmp(before.data(), m.decoded.data(), before.pixel_count() * sizeof(float)));
    }
}

TEST(PhaseErrorCorrection, AnAliasedFrontoParallelGridIsNotMistakenForAnError) {
    // Every row samples the fold at exactly 4 phases (a quarter sub-period
    // per pixel): the fold's histogram has four spikes, which the plain
    // distribution estimate reads as a large error at harmonic 4. With a
    // linear response there is none to correct.
    const fpp::PhaseBlock b = block(3, 20.0);
    const double unit = b.period / b.steps;
    fpp::Image<float> proj(320, 240);
    for (int y = 0; y < 240; ++y)
        for (int x = 0; x < 320; ++x)
            proj.at(x, y) = static_cast<float>(unit * (0.25 * x + 0.1));
    const fpp::Image<std::uint8_t> mask(320, 240, 1, fpp::kDecodeValid);
    fpp::PhaseErrorOptions plain;
    plain.debias_sampling = false;
    const fpp::PhaseErrorSummary naive = fpp::estimate_phase_error(proj, mask, b, plain);
    const fpp::Image<float> before = proj;
    const fpp::PhaseErrorSummary s = fpp::correct_phase_error(proj, mask, b);
    std::printf("[ figures  ] aliased grid: plain estimate %.4f px RMS (%s); with the "
                "stand-in: %s\n",
                naive.rms_px, naive.applied ? "applied" : naive.reason.c_str(),
                fpp::describe(s).c_str());
    EXPECT_GT(naive.rms_px + naive.asymmetry_px, 0.1); // the trap is real
    EXPECT_FALSE(s.applied);
    EXPECT_NE(s.reason.find("aliases"), std::string::npos) << s.reason;
    EXPECT_EQ(0, std::memcmp(before.data(), proj.data(), before.pixel_count() * sizeof(float)));
}

TEST(PhaseErrorCorrection, IsContinuousAcrossTheSubPeriodSeam) {
    const fpp::PhaseBlock b = block(3, 20.0);
    Maps m = make_maps(b, gamma22);
    const fpp::PhaseErrorSummary s = fpp::estimate_phase_error(m.decoded, m.mask, b);
    ASSERT_TRUE(s.applied) << s.reason;
    EXPECT_NEAR(fpp::phase_error_correction_at(s, 0.0), fpp::phase_error_correction_at(s, 1.0),
                1e-12);
    EXPECT_NEAR(fpp::phase_error_correction_at(s, 1e-6),
                fpp::phase_error_correction_at(s, 1.0 - 1e-6), 1e-4);
    // Through the lookup table: a row of coordinates densely crossing
    // several sub-period boundaries maps to a strictly increasing row with
    // no jump larger than the slope allows.
    constexpr int n = 4000;
    fpp::Image<float> row(n, 1);
    const double step = 3 * b.period / n; // three fringes, nine seams
    for (int i = 0; i < n; ++i)
        row.at(i, 0) = static_cast<float>(100.0 + i * step);
    fpp::apply_phase_error_correction(row, b, s);
    double largest = 0, smallest = 1e9;
    for (int i = 1; i < n; ++i) {
        const double d = double(row.at(i, 0)) - double(row.at(i - 1, 0));
        largest = std::max(largest, d / step);
        smallest = std::min(smallest, d / step);
    }
    std::printf("[ figures  ] corrected slope over the seams: %.3f .. %.3f (fitted %.3f ..)\n",
                smallest, largest, s.min_slope);
    EXPECT_GT(smallest, 0.3);
    EXPECT_LT(largest, 4.0);
}

TEST(PhaseErrorCorrection, KeepsNaNAndDoesNotDependOnThreads) {
    const fpp::PhaseBlock b = block(3, 20.0);
    Maps m = make_maps(b, gamma22);
    for (int y = 100; y < 140; ++y)
        for (int x = 0; x < 320; ++x) {
            m.decoded.at(x, y) = kNaN;
            m.mask.at(x, y) = fpp::kDecodeLowModulation;
        }
    fpp::Image<float> single = m.decoded;
    const fpp::PhaseErrorSummary a = fpp::correct_phase_error(single, m.mask, b);
    fpp::ThreadPool pool(3);
    fpp::Image<float> parallel = m.decoded;
    const fpp::PhaseErrorSummary c = fpp::correct_phase_error(parallel, m.mask, b, {}, &pool);
    ASSERT_TRUE(a.applied);
    EXPECT_EQ(a.sine, c.sine);
    EXPECT_EQ(0, std::memcmp(single.data(), parallel.data(), single.pixel_count() * sizeof(float)));
    for (int x = 0; x < 320; ++x)
        EXPECT_TRUE(std::isnan(single.at(x, 120)));
}

TEST(PhaseErrorCorrection, RefusesBadOptionsAndBlocks) {
    const fpp::PhaseBlock b = block(3, 20.0);
    Maps m = make_maps(b, linear, 64, 48);
    fpp::PhaseErrorOptions o;
    o.harmonics = 0;
    try {
        fpp::estimate_phase_error(m.decoded, m.mask, b, o);
        FAIL() << "harmonics = 0 accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("harmonics"), std::string::npos) << e.what();
    }
    o = {};
    o.min_slope = 1.5;
    EXPECT_THROW(fpp::estimate_phase_error(m.decoded, m.mask, b, o), std::invalid_argument);
    EXPECT_THROW(fpp::estimate_phase_error(m.decoded, m.mask, block(2, 20.0)),
                 std::invalid_argument);
    EXPECT_THROW(fpp::estimate_phase_error(m.decoded, fpp::Image<std::uint8_t>(10, 10), b),
                 std::invalid_argument);
    fpp::DecodeOptions d; // the decoder's options name the field as an InputError
    d.phase_error.harmonics = 99;
    EXPECT_THROW(d.validate(), fpp::InputError);
}

// ---------------------------------------------------------------------------
// Through the decoder: 8-step phase of periods 1280 and 160, then 3-step
// of period 20 (multi-period), frames synthesised with gamma 2.2 and 8-bit
// rounding.

fpp::CaptureSet synthetic_capture(int width, int height) {
    fpp::CaptureSet set;
    set.manifest.camera = {width, height};
    set.manifest.projector = {1280, 800};
    // The cues have 8 steps: with 3, their own gamma error (up to 4.6 % of
    // a period) would break the unwrapping at many pixels.
    const fpp::PhaseBlock fine = block(3, 20.0);
    const fpp::PhaseBlock middle = block(8, 160.0);
    const fpp::PhaseBlock coarse = block(8, 1280.0);
    set.manifest.sequence = {coarse, middle, fine};
    for (const fpp::PhaseBlock& b : {coarse, middle, fine})
        for (int k = 0; k < b.steps; ++k) {
            fpp::Frame f;
            f.bit_depth = 8;
            f.u8 = fpp::Image<std::uint8_t>(width, height);
            for (int y = 0; y < height; ++y)
                for (int x = 0; x < width; ++x) {
                    const double theta = 2 * kPi * true_column(x, y) / b.period +
                                         b.shift_sign * 2 * kPi * k / b.steps;
                    const double level = gamma22(0.5 + 0.5 * std::cos(theta));
                    f.u8.at(x, y) = static_cast<std::uint8_t>(std::lround(20 + 200 * level));
                }
            set.frames.push_back(std::move(f));
            char name[32];
            std::snprintf(name, sizeof name, "f%zu.png", set.frames.size());
            set.manifest.frames.emplace_back(name);
        }
    return set;
}

TEST(PhaseErrorCorrection, DecoderOptionCorrectsBatchAndStreamingAlike) {
    const fpp::CaptureSet set = synthetic_capture(320, 240);
    fpp::Image<float> truth(320, 240);
    for (int y = 0; y < 240; ++y)
        for (int x = 0; x < 320; ++x)
            truth.at(x, y) = static_cast<float>(true_column(x, y));
    const fpp::DecodeResult plain = fpp::decode(set);
    EXPECT_FALSE(plain.phase_correction_x.attempted);
    fpp::DecodeOptions options;
    options.correct_phase_error = true;
    const fpp::DecodeResult corrected = fpp::decode(set, options);
    fpp::StreamingDecoder streaming(set.manifest.sequence, set.manifest.camera,
                                    set.manifest.projector, options);
    for (const fpp::Frame& f : set.frames)
        streaming.push(f);
    const fpp::DecodeResult streamed = streaming.finish();
    const double before = rms_error(plain.proj_x, truth);
    const double after = rms_error(corrected.proj_x, truth);
    std::printf("[ figures  ] decoder, 3 steps, gamma 2.2, 8-bit: RMS %.4f -> %.4f px; %s\n",
                before, after, fpp::describe(corrected.phase_correction_x).c_str());
    ASSERT_TRUE(corrected.phase_correction_x.applied) << corrected.phase_correction_x.reason;
    EXPECT_FALSE(corrected.phase_correction_y.attempted); // y not coded
    EXPECT_GT(before, 0.5);
    EXPECT_LT(after, 0.05); // 8-bit rounding of 200 DN fringes: ~0.02 px
    EXPECT_EQ(0, std::memcmp(plain.mask.data(), corrected.mask.data(), plain.mask.pixel_count()));
    EXPECT_EQ(0, std::memcmp(corrected.proj_x.data(), streamed.proj_x.data(),
                             corrected.proj_x.pixel_count() * sizeof(float)));
    EXPECT_EQ(corrected.phase_correction_x.sine, streamed.phase_correction_x.sine);
    // Decoding into a recycled result reports this decode's correction.
    fpp::DecodeResult recycled = corrected;
    fpp::decode(set, recycled);
    EXPECT_FALSE(recycled.phase_correction_x.attempted);
    EXPECT_EQ(0, std::memcmp(plain.proj_x.data(), recycled.proj_x.data(),
                             plain.proj_x.pixel_count() * sizeof(float)));
}

} // namespace
