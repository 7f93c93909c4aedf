// Renderer: phase decoded from noise-free renders matches the ground truth;
// radiometry (white level, gamma, falloff, ambient, shadows, defocus); noise
// statistics, reproducibility, bit depths, saturation; whole simulated
// capture sets written and read back.

#include "fpp/capture_set.hpp"
#include "fpp/image_io.hpp"
#include "fpp/simulator/renderer.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <filesystem>

namespace {

using fpp::Frame;
using fpp::Image;
using fpp::Size;
using fpp::Vec2;
using fpp::Vec3;
using namespace fpp::sim;

constexpr double kPi = 3.14159265358979323846;

// The spec's phase pattern: I_k(p) = 1/2 + 1/2 cos(2 pi p / period + 2 pi k / N), 8-bit.
Image<std::uint8_t> phase_pattern(Size size, bool along_x, double period, int steps, int k) {
    Image<std::uint8_t> img(size);
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x) {
            const double p = along_x ? x : y;
            const double I = 0.5 + 0.5 * std::cos(2 * kPi * p / period + 2 * kPi * k / steps);
            img.at(x, y) = static_cast<std::uint8_t>(std::lround(255 * I));
        }
    return img;
}

Image<std::uint8_t> uniform(Size size, int level) {
    return Image<std::uint8_t>(size, 1, static_cast<std::uint8_t>(level));
}

double sample(const Frame& f, int x, int y) {
    return f.bit_depth == 8 ? f.u8.at(x, y) : f.u16.at(x, y);
}

// A small, fast rig: the paper's geometry with 4 x 4 binning (400 x 300).
Rig small_rig() {
    return Rig::paper().binned_camera(4);
}

struct PhaseStats {
    double rms = 0, max = 0;
    long pixels = 0;
};

// Decodes the N-step phase of `frames` per pixel with the spec's formula,
// unwraps it with the truth and compares with the truth projector coordinate.
PhaseStats decode_against_truth(const Renderer& r, bool along_x, double period, int steps,
                                double min_modulation) {
    std::vector<Frame> frames;
    for (int k = 0; k < steps; ++k)
        frames.push_back(
            r.render(phase_pattern(r.rig().projector_size, along_x, period, steps, k), 7));
    const Image<float>& truth = r.truth_projector();
    PhaseStats s;
    double sum2 = 0;
    const Size pz = r.rig().projector_size;
    for (int y = 0; y < truth.height(); ++y)
        for (int x = 0; x < truth.width(); ++x) {
            const double tp = truth.at(x, y, along_x ? 0 : 1);
            if (std::isnan(tp))
                continue;
            // Away from the projector image's edge, where the bilinear sample is clamped.
            const double other = truth.at(x, y, along_x ? 1 : 0);
            const double extent = along_x ? pz.width : pz.height;
            const double other_extent = along_x ? pz.height : pz.width;
            if (tp < 1 || tp > extent - 2 || other < 1 || other > other_extent - 2)
                continue;
            std::complex<double> acc;
            for (int k = 0; k < steps; ++k) {
                const double delta = 2 * kPi * k / steps;
                acc += sample(frames[static_cast<std::size_t>(k)], x, y) *
                       std::complex<double>(std::cos(delta), -std::sin(delta));
            }
            const double modulation = 2 * std::abs(acc) / steps;
            if (modulation < min_modulation)
                continue;
            const double theta =
                std::atan2(acc.imag(), acc.real()); // = atan2(-sum I sin, sum I cos)
            const double phi_true = 2 * kPi * tp / period;
            const double phi = theta + 2 * kPi * std::round((phi_true - theta) / (2 * kPi));
            const double err = phi * period / (2 * kPi) - tp;
            sum2 += err * err;
            s.max = std::max(s.max, std::fabs(err));
            ++s.pixels;
        }
    s.rms = s.pixels ? std::sqrt(sum2 / static_cast<double>(s.pixels)) : 0;
    return s;
}

TEST(SimRenderer, NoiseFreePhaseDecodesToTheTruthOnAPlane) {
    const Renderer r(small_rig(), named_scene("plane"));
    for (bool along_x : {true, false}) {
        const PhaseStats s = decode_against_truth(r, along_x, 20, 8, 20);
        EXPECT_GT(s.pixels, 110000);
        EXPECT_LT(s.rms, 0.02) << (along_x ? "x" : "y");
        EXPECT_LT(s.max, 0.1);
        std::printf("plane, 8-step period 20 along %s: RMS %.4f px, max %.4f px over %ld pixels\n",
                    along_x ? "x" : "y", s.rms, s.max, s.pixels);
        RecordProperty(along_x ? "decode_rms_x" : "decode_rms_y", std::to_string(s.rms));
    }
}

TEST(SimRenderer, NoiseFreePhaseDecodesToTheTruthOnTheComposite) {
    const Renderer r(small_rig(), named_scene("composite"));
    const PhaseStats s = decode_against_truth(r, true, 20, 8, 40);
    EXPECT_GT(s.pixels, 60000);
    EXPECT_LT(s.rms, 0.02);
    std::printf("composite, 8-step period 20 along x: RMS %.4f px, max %.4f px over %ld pixels\n",
                s.rms, s.max, s.pixels);
}

TEST(SimRenderer, TruthIsConsistentWithBothLenses) {
    const Rig rig = small_rig();
    const Renderer r(rig, named_scene("composite"));
    long lit = 0, shadowed = 0, none = 0;
    for (int y = 0; y < rig.camera_size.height; ++y)
        for (int x = 0; x < rig.camera_size.width; ++x) {
            const Vec3 X{r.truth_xyz().at(x, y, 0), r.truth_xyz().at(x, y, 1),
                         r.truth_xyz().at(x, y, 2)};
            if (std::isnan(X[0])) {
                ++none;
                EXPECT_TRUE(std::isnan(r.truth_projector().at(x, y, 0)));
                continue;
            }
            const Vec2 cam = rig.camera.project(X);
            EXPECT_NEAR(cam[0], x, 2e-3);
            EXPECT_NEAR(cam[1], y, 2e-3);
            const double px = r.truth_projector().at(x, y, 0);
            if (std::isnan(px)) {
                ++shadowed;
                EXPECT_TRUE(std::isnan(r.truth_projector().at(x, y, 1)));
                continue;
            }
            ++lit;
            const Vec3 Xr = fpp::mul(rig.R, X);
            const Vec2 p =
                rig.projector.project({Xr[0] + rig.t[0], Xr[1] + rig.t[1], Xr[2] + rig.t[2]});
            EXPECT_NEAR(p[0], px, 2e-3);
            EXPECT_NEAR(p[1], r.truth_projector().at(x, y, 1), 2e-3);
        }
    EXPECT_EQ(none, 0);        // the background plane fills the field
    EXPECT_GT(shadowed, 4000); // shadows of the sphere and the relief, and the bottom rows
    EXPECT_GT(lit, 100000);
}

TEST(SimRenderer, ShadowAndOcclusionInTheComposite) {
    Rig rig = small_rig();
    rig.sensor.ambient = 20;
    const Renderer r(rig, named_scene("composite"));
    const Image<float> white = r.render_radiance(uniform(rig.projector_size, 255));
    const Vec3 pc = rig.projector_centre_in_camera();
    const Vec3 s{80, 25, 450};
    const double radius = 38;
    long blocked = 0, open = 0;
    for (int y = 0; y < rig.camera_size.height; ++y)
        for (int x = 0; x < rig.camera_size.width; ++x) {
            const Vec3 X{r.truth_xyz().at(x, y, 0), r.truth_xyz().at(x, y, 1),
                         r.truth_xyz().at(x, y, 2)};
            if (std::fabs(X[2] - 540) > 1e-3)
                continue; // background plane pixels only
            // Does the segment from X to the projector centre pass through the sphere?
            const Vec3 d{pc[0] - X[0], pc[1] - X[1], pc[2] - X[2]};
            const double len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            const double u =
                ((s[0] - X[0]) * d[0] + (s[1] - X[1]) * d[1] + (s[2] - X[2]) * d[2]) / len2;
            const Vec3 c{X[0] + u * d[0] - s[0], X[1] + u * d[1] - s[1], X[2] + u * d[2] - s[2]};
            const double miss = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
            if (miss < radius - 0.5 && u > 0 && u < 1) {
                ++blocked;
                EXPECT_TRUE(std::isnan(r.truth_projector().at(x, y, 0))) << x << " " << y;
                EXPECT_NEAR(white.at(x, y), 20 * 0.85, 1e-4); // ambient only
            } else if (miss > radius + 0.5 && X[0] > 40) {
                // Right of the relief (whose shadows fall to the left) and
                // inside the projector image with a margin: lit.
                const Vec3 Xr = fpp::mul(rig.R, X);
                const Vec2 p =
                    rig.projector.project({Xr[0] + rig.t[0], Xr[1] + rig.t[1], Xr[2] + rig.t[2]});
                if (p[0] < 1 || p[0] > 1278 || p[1] < 1 || p[1] > 798)
                    continue;
                ++open;
                EXPECT_FALSE(std::isnan(r.truth_projector().at(x, y, 0))) << x << " " << y;
                EXPECT_GT(white.at(x, y), 150.0f);
            }
        }
    EXPECT_GT(blocked, 300);
    EXPECT_GT(open, 10000);
    // Occlusion edge: along the row through the sphere's centre the depth
    // jumps once, from the sphere to the plane.
    const Vec2 c = rig.camera.project(s);
    const int row = static_cast<int>(std::lround(c[1]));
    int jumps = 0;
    for (int u = static_cast<int>(c[0]); u + 1 < rig.camera_size.width; ++u) {
        const float z0 = r.truth_xyz().at(u, row, 2), z1 = r.truth_xyz().at(u + 1, row, 2);
        if (z1 - z0 > 50)
            ++jumps;
    }
    EXPECT_EQ(jumps, 1);
}

TEST(SimRenderer, CheckerboardEdgesAreAreaSampled) {
    // A pixel that an edge of the print crosses sees the albedos mixed in
    // proportion to the areas on each side, so that corner detection gets
    // sub-pixel information as from a real sensor.
    const Rig rig = Rig::paper().binned_camera(2);
    CheckerboardSpec spec;
    const Pose pose = Pose::from_euler_deg({-10, 5, 470}, 15, -20, 4);
    const Scene scene = checkerboard_scene(pose, spec);
    const Renderer r(rig, scene);
    const Checkerboard board(pose, spec);
    const double s = spec.square_size;
    auto pixel_of = [&](double x, double y) {
        return rig.camera.project(pose.to_camera({x, y, 0}));
    };
    int checked = 0;
    double worst = 0;
    for (int row = 0; row <= spec.inner_rows; row += 3) {
        // Middle of square row `row`, far from horizontal edges.
        const double y_mid = (row - 0.5 - (spec.inner_rows - 1) * 0.5) * s;
        for (int i = 0; i < spec.inner_columns; i += 2) {
            const double x_edge = (i - (spec.inner_columns - 1) * 0.5) * s;
            const int v = static_cast<int>(std::lround(pixel_of(x_edge, y_mid)[1]));
            // The board y at which the edge line crosses image row v (bisection).
            double lo = y_mid - s / 2, hi = y_mid + s / 2;
            for (int k = 0; k < 100; ++k) {
                const double mid = 0.5 * (lo + hi);
                ((pixel_of(x_edge, mid)[1] < v) == (pixel_of(x_edge, lo)[1] < v) ? lo : hi) = mid;
            }
            const double y_at_v = 0.5 * (lo + hi);
            const Vec2 on_row = pixel_of(x_edge, y_at_v);
            const int u = static_cast<int>(std::lround(on_row[0]));
            // The edge is a straight line across the pixel, u = u0 + k (v' - v);
            // the part of the pixel left of it, integrated over the pixel's height.
            const Vec2 below = pixel_of(x_edge, y_at_v + 0.01),
                       above = pixel_of(x_edge, y_at_v - 0.01);
            const double k = (below[0] - above[0]) / (below[1] - above[1]);
            double left = 0;
            constexpr int kRows = 2000;
            for (int j = 0; j < kRows; ++j) {
                const double dv = (j + 0.5) / kRows - 0.5;
                left += std::clamp(on_row[0] + k * dv - (u - 0.5), 0.0, 1.0) / kRows;
            }
            const double a_left = board.albedo_at(x_edge - 1, y_at_v);
            const double a_right = board.albedo_at(x_edge + 1, y_at_v);
            ASSERT_NE(a_left, a_right);
            const double expected = left * a_left + (1 - left) * a_right;
            const double got = r.albedo().at(u, v);
            worst = std::max(worst, std::fabs(got - expected));
            ++checked;
        }
    }
    EXPECT_GT(checked, 30);
    // 5e-4 of the albedo step of 0.85 is 1/1700 of a pixel in edge position.
    EXPECT_LT(worst, 5e-4);
    std::printf("checkerboard edges: %d pixels, worst albedo error %.2g\n", checked, worst);
}

TEST(SimRenderer, WhiteLevelShadingAndAmbient) {
    Rig rig = small_rig();
    rig.sensor.ambient = 10;
    const Renderer r(rig, named_scene("plane"));
    const Image<float> white = r.render_radiance(uniform(rig.projector_size, 255));
    const Image<float> black = r.render_radiance(uniform(rig.projector_size, 0));
    const Vec3 pc = rig.projector_centre_in_camera();
    for (int y = 5; y < 300; y += 37)
        for (int x = 3; x < 400; x += 41) {
            const Vec3 X{r.truth_xyz().at(x, y, 0), r.truth_xyz().at(x, y, 1),
                         r.truth_xyz().at(x, y, 2)};
            const Vec3 l{pc[0] - X[0], pc[1] - X[1], pc[2] - X[2]};
            const double cos_inc =
                -l[2] / std::sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]); // normal -z
            EXPECT_NEAR(white.at(x, y), 240 * 0.9 * cos_inc + 10 * 0.9, 1e-3);
            EXPECT_NEAR(black.at(x, y), 10 * 0.9, 1e-4);
        }
    // White on albedo 0.9 at 480 mm is about 200 DN in the paper rig.
    EXPECT_NEAR(white.at(200, 150) - 9, 200, 5);
}

TEST(SimRenderer, GammaBlackLevelAndFalloff) {
    Rig rig = small_rig();
    rig.projector_optics.gamma = 2.2;
    rig.projector_optics.black_level = 0.01;
    rig.sensor.reference_distance_mm = 600;
    const Renderer r(rig, named_scene("inclined-plane"));
    const Image<float> full = r.render_radiance(uniform(rig.projector_size, 255));
    const Image<float> mid = r.render_radiance(uniform(rig.projector_size, 128));
    Rig flat = rig;
    flat.sensor.reference_distance_mm = 0;
    const Renderer rf(flat, named_scene("inclined-plane"));
    const Image<float> full_flat = rf.render_radiance(uniform(rig.projector_size, 255));
    const Vec3 pc = rig.projector_centre_in_camera();
    const double expected_ratio = (std::pow(128 / 255.0, 2.2) + 0.01) / 1.01;
    int checked = 0;
    for (int y = 10; y < 300; y += 40)
        for (int x = 10; x < 400; x += 40) {
            if (std::isnan(r.truth_projector().at(x, y, 0)))
                continue;
            ++checked;
            EXPECT_NEAR(mid.at(x, y) / full.at(x, y), expected_ratio, 1e-5);
            const Vec3 X{r.truth_xyz().at(x, y, 0), r.truth_xyz().at(x, y, 1),
                         r.truth_xyz().at(x, y, 2)};
            const double d =
                std::sqrt((pc[0] - X[0]) * (pc[0] - X[0]) + (pc[1] - X[1]) * (pc[1] - X[1]) +
                          (pc[2] - X[2]) * (pc[2] - X[2]));
            EXPECT_NEAR(full.at(x, y) / full_flat.at(x, y), (600 / d) * (600 / d), 1e-4);
        }
    EXPECT_GT(checked, 50);
}

// Modulation (DN) per pixel of an N-step phase set rendered noise-free.
Image<float> modulation(const Renderer& r, double period, int steps) {
    const Size cam = r.rig().camera_size;
    std::vector<std::complex<double>> acc(cam.area());
    for (int k = 0; k < steps; ++k) {
        const Image<float> img =
            r.render_radiance(phase_pattern(r.rig().projector_size, true, period, steps, k));
        const double delta = 2 * kPi * k / steps;
        for (std::size_t i = 0; i < acc.size(); ++i)
            acc[i] += static_cast<double>(img.data()[i]) * std::polar(1.0, -delta);
    }
    Image<float> m(cam);
    for (std::size_t i = 0; i < acc.size(); ++i)
        m.data()[i] = static_cast<float>(2 * std::abs(acc[i]) / steps);
    return m;
}

TEST(SimRenderer, ProjectorDefocusIsAGaussianBlurOfTheProjectorImage) {
    Rig rig = small_rig();
    const Renderer sharp(rig, named_scene("plane"));
    rig.projector_optics.defocus_sigma_px = 0.8;
    const Renderer blurred(rig, named_scene("plane"));
    const double period = 8;
    const Image<float> m0 = modulation(sharp, period, 8), m1 = modulation(blurred, period, 8);
    // A Gaussian of sigma s passes a sinusoid of period P with gain exp(-2 pi^2 s^2 / P^2).
    const double expected = std::exp(-2 * kPi * kPi * 0.64 / (period * period));
    double sum = 0;
    long n = 0;
    for (int y = 20; y < 280; y += 3)
        for (int x = 20; x < 380; x += 3) {
            sum += static_cast<double>(m1.at(x, y) / m0.at(x, y));
            ++n;
        }
    EXPECT_NEAR(sum / static_cast<double>(n), expected, 0.01);
}

TEST(SimRenderer, CameraDefocusIsAGaussianBlurOfTheImage) {
    Rig rig = small_rig();
    const Renderer sharp(rig, named_scene("composite"));
    const double sigma = 1.3;
    rig.sensor.defocus_sigma_px = sigma;
    const Renderer blurred(rig, named_scene("composite"));
    const auto pattern = phase_pattern(rig.projector_size, true, 20, 4, 1);
    const Image<float> a = sharp.render_radiance(pattern), b = blurred.render_radiance(pattern);
    // Direct 2D convolution with a Gaussian at interior pixels.
    const int r = 6;
    for (int y = 30; y < 270; y += 23)
        for (int x = 30; x < 370; x += 29) {
            double sum = 0, wsum = 0;
            for (int j = -r; j <= r; ++j)
                for (int i = -r; i <= r; ++i) {
                    const double w = std::exp(-0.5 * (i * i + j * j) / (sigma * sigma));
                    sum += w * static_cast<double>(a.at(x + i, y + j));
                    wsum += w;
                }
            EXPECT_NEAR(b.at(x, y), sum / wsum, 0.2) << x << " " << y;
        }
}

TEST(SimRenderer, ReadNoiseHasTheConfiguredSigma) {
    Rig rig = small_rig();
    rig.sensor.bit_depth = 12;
    rig.sensor.white_level = 3000;
    rig.sensor.read_noise_dn = 3.0;
    const Renderer r(rig, named_scene("plane"));
    const auto grey = uniform(rig.projector_size, 128);
    // Half the variance of the difference of two renders with different
    // seeds is the noise variance, free of the signal's variation.
    const Frame a = r.render(grey, 11), b = r.render(grey, 12);
    double sum2 = 0;
    long beyond = 0, n = 0;
    for (int y = 0; y < 300; ++y)
        for (int x = 0; x < 400; ++x) {
            const double d = (sample(a, x, y) - sample(b, x, y)) / 16.0; // 12-bit DN
            sum2 += d * d;
            if (std::fabs(d) > 2 * std::sqrt(2.0) * 3.0)
                ++beyond;
            ++n;
        }
    // Rounding to integer DN adds 1/12 DN^2 to each frame's variance.
    const double sigma = std::sqrt(sum2 / (2.0 * static_cast<double>(n)) - 1.0 / 12);
    EXPECT_NEAR(sigma, 3.0, 0.3);  // the 10 % of the requirement ...
    EXPECT_NEAR(sigma, 3.0, 0.05); // ... and what 120 000 samples resolve
    // Gaussian tails: P(|z| > 2) = 4.55 %.
    EXPECT_NEAR(static_cast<double>(beyond) / static_cast<double>(n), 0.0455, 0.004);
    std::printf("read noise: configured 3.000 DN, measured %.3f DN\n", sigma);
}

TEST(SimRenderer, ShotNoiseVarianceIsSignalOverGain) {
    Rig rig = small_rig();
    rig.sensor.bit_depth = 12;
    rig.sensor.white_level = 3500;
    rig.sensor.read_noise_dn = 1.0;
    rig.sensor.gain_e_per_dn = 2.0;
    const Renderer r(rig, named_scene("plane"));
    // Levels rising along projector x give signals from 0 to ~3000 DN.
    Image<std::uint8_t> ramp(rig.projector_size);
    for (int y = 0; y < ramp.height(); ++y)
        for (int x = 0; x < ramp.width(); ++x)
            ramp.at(x, y) = static_cast<std::uint8_t>(x * 255 / 1279);
    const Image<float> mean = r.render_radiance(ramp);
    const Frame a = r.render(ramp, 1), b = r.render(ramp, 2);
    // Bins of 500 DN of signal.
    double sum2[8] = {}, signal[8] = {};
    long count[8] = {};
    for (int y = 0; y < 300; ++y)
        for (int x = 0; x < 400; ++x) {
            const double s = static_cast<double>(mean.at(x, y));
            const int bin = static_cast<int>(s / 500);
            if (bin < 0 || bin >= 8)
                continue;
            const double d = (sample(a, x, y) - sample(b, x, y)) / 16.0;
            sum2[bin] += d * d;
            signal[bin] += s;
            ++count[bin];
        }
    int bins = 0;
    for (int k = 0; k < 8; ++k) {
        if (count[k] < 5000)
            continue;
        ++bins;
        const double var = sum2[k] / (2.0 * static_cast<double>(count[k])) - 1.0 / 12;
        const double expected = signal[k] / static_cast<double>(count[k]) / 2.0 + 1.0;
        EXPECT_NEAR(var / expected, 1.0, 0.1) << "bin " << k;
    }
    EXPECT_GE(bins, 3);
}

TEST(SimRenderer, NoiseIsReproducibleAndIndependentOfThreads) {
    Rig rig = fpp::sim::load_rig(effects_rig_path()).binned_camera(4);
    const Renderer one(rig, named_scene("composite"), 1);
    const Renderer three(rig, named_scene("composite"), 3);
    const auto pattern = phase_pattern(rig.projector_size, false, 20, 8, 3);
    const Frame a = one.render(pattern, 42), b = one.render(pattern, 42),
                c = three.render(pattern, 42);
    EXPECT_EQ(a.u8.storage(), b.u8.storage());
    EXPECT_EQ(a.u8.storage(), c.u8.storage());
    EXPECT_EQ(one.truth_projector().storage().size(), three.truth_projector().storage().size());
    const Frame d = one.render(pattern, 43);
    long differ = 0;
    for (std::size_t i = 0; i < a.u8.storage().size(); ++i)
        differ += a.u8.storage()[i] != d.u8.storage()[i];
    EXPECT_GT(differ, 20000);
    EXPECT_NE(Renderer::frame_seed(1, 0), Renderer::frame_seed(1, 1));
    EXPECT_NE(Renderer::frame_seed(1, 0), Renderer::frame_seed(2, 0));
}

TEST(SimRenderer, BitDepthsAreMsbAligned) {
    for (int depth : {8, 10, 12, 16}) {
        Rig rig = Rig::paper().binned_camera(8);
        rig.sensor.bit_depth = depth;
        rig.sensor.white_level = 0.8 * (std::ldexp(1.0, depth) - 1);
        const Renderer r(rig, named_scene("composite"));
        const auto pattern = phase_pattern(rig.projector_size, true, 20, 8, 2);
        const Frame f = r.render(pattern, 3);
        const Image<float> radiance = r.render_radiance(pattern);
        ASSERT_EQ(f.bit_depth, depth == 8 ? 8 : 16);
        ASSERT_EQ(f.size(), rig.camera_size);
        const int shift = depth == 8 ? 0 : 16 - depth;
        for (int y = 0; y < f.size().height; ++y)
            for (int x = 0; x < f.size().width; ++x) {
                const unsigned v = static_cast<unsigned>(sample(f, x, y));
                EXPECT_EQ(v % (1u << shift), 0u);
                // Noise-free: the nearest DN of the radiance, at the top bits.
                EXPECT_NEAR(static_cast<double>(v >> shift), radiance.at(x, y), 0.5 + 1e-2);
            }
    }
}

TEST(SimRenderer, SaturationClipsAtFullScale) {
    for (int depth : {8, 12}) {
        Rig rig = Rig::paper().binned_camera(8);
        rig.sensor.bit_depth = depth;
        const double full = std::ldexp(1.0, depth) - 1;
        rig.sensor.white_level = 2.5 * full;
        rig.sensor.read_noise_dn = 2;
        const Renderer r(rig, named_scene("composite"));
        const auto white = uniform(rig.projector_size, 255);
        const Frame f = r.render(white, 5);
        const Image<float> radiance = r.render_radiance(white);
        const double top = depth == 8 ? 255.0 : 65520.0;
        long saturated = 0;
        for (int y = 0; y < f.size().height; ++y)
            for (int x = 0; x < f.size().width; ++x) {
                const double v = sample(f, x, y);
                EXPECT_LE(v, top);
                if (static_cast<double>(radiance.at(x, y)) >
                    full + 10) { // far above full scale even with noise
                    EXPECT_EQ(v, top);
                    ++saturated;
                }
            }
        EXPECT_GT(saturated, 3000);
    }
}

TEST(SimRenderer, RejectsAProjectorImageOfTheWrongSize) {
    const Rig rig = Rig::paper().binned_camera(16);
    const Renderer r(rig, named_scene("plane"));
    EXPECT_THROW(r.render(Image<std::uint8_t>(640, 400), 1), std::invalid_argument);
    EXPECT_THROW(r.render(Image<std::uint8_t>(rig.projector_size, 3), 1), std::invalid_argument);
}

// ---- whole captures -------------------------------------------------------

TEST(SimCapture, SimulateWritesAReadableCaptureSetWithTruth) {
    Rig rig = fpp::sim::load_rig(effects_rig_path()).binned_camera(8);
    rig.sensor.bit_depth = 12;
    const fpp::Sequence sequence{fpp::WhiteBlock{}, fpp::BlackBlock{},
                                 fpp::PhaseBlock{fpp::Axis::x, 20.0, 4, 1, 0.0}};
    const SimulatedCapture cap = simulate(rig, named_scene("composite"), sequence, 9);
    ASSERT_EQ(cap.frames.size(), 6u);
    EXPECT_EQ(cap.manifest.frames[0], "000.png");
    EXPECT_EQ(cap.manifest.frames[5], "005.png");
    EXPECT_EQ(cap.frames[0].bit_depth, 16);
    ASSERT_TRUE(cap.manifest.truth.has_value());
    // Reproducible with the same seed.
    const SimulatedCapture again = simulate(rig, named_scene("composite"), sequence, 9);
    EXPECT_EQ(again.frames[3].u16.storage(), cap.frames[3].u16.storage());
    // The white frame is brighter than the black one where lit.
    const int cx = 100, cy = 75;
    ASSERT_FALSE(std::isnan(cap.truth_projector.at(cx, cy, 0)));
    EXPECT_GT(cap.frames[0].u16.at(cx, cy), cap.frames[1].u16.at(cx, cy) + 16 * 100);

    fpp::test::TempDir dir;
    const auto folder = dir / "pose-00";
    write_simulated_capture(folder, cap);
    const fpp::CaptureSet back = fpp::read_capture_set(folder);
    EXPECT_EQ(back.manifest.camera, rig.camera_size);
    EXPECT_EQ(back.manifest.projector, rig.projector_size);
    EXPECT_EQ(back.manifest.sequence, sequence);
    ASSERT_TRUE(back.manifest.truth.has_value());
    EXPECT_EQ(back.manifest.truth->xyz, "truth_xyz.tiff");
    EXPECT_EQ(back.manifest.truth->projector, "truth_proj.tiff");
    ASSERT_EQ(back.frames.size(), cap.frames.size());
    for (std::size_t i = 0; i < cap.frames.size(); ++i)
        EXPECT_EQ(back.frames[i].u16.storage(), cap.frames[i].u16.storage()) << i;
    const Image<float> xyz = fpp::read_tiff_float(folder / "truth_xyz.tiff");
    const Image<float> proj = fpp::read_tiff_float(folder / "truth_proj.tiff");
    ASSERT_EQ(xyz.channels(), 3);
    ASSERT_EQ(proj.channels(), 2);
    ASSERT_EQ(xyz.storage().size(), cap.truth_xyz.storage().size());
    ASSERT_EQ(proj.storage().size(), cap.truth_projector.storage().size());
    for (std::size_t i = 0; i < proj.storage().size(); ++i) {
        const float a = proj.storage()[i], b = cap.truth_projector.storage()[i];
        ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << i;
    }
    for (std::size_t i = 0; i < xyz.storage().size(); ++i)
        ASSERT_EQ(xyz.storage()[i], cap.truth_xyz.storage()[i]);
    // Nothing else in the parent: no temporary folder left behind.
    int entries = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
        (void)e;
        ++entries;
    }
    EXPECT_EQ(entries, 1);
    // The folder must not exist yet.
    EXPECT_ANY_THROW(write_simulated_capture(folder, cap));
}

} // namespace
