// The device path of the projector response on the virtual scanner: a ramp
// of grey levels on the flat board, the response fitted from it, and 3-, 4-
// and 8-step sequences rendered through its inverse, decoded and compared
// with the truth against the same sequences on a linear projector.
//
// Rig: the effects rig (gamma 2.2, 0.5 % black level, shot and read noise,
// defocus), camera binned 4x (400 x 300). Linear reference: the same rig with
// gamma 1; its black level (0.5 %) is kept, so that the two differ only in
// the curve the compensation has to undo. Every run of a sequence uses the
// same noise seeds.

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/patterns.hpp"
#include "fpp/projector_response.hpp"
#include "fpp/sequences.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

using namespace fpp;

namespace {

// White, black, an N-step phase block of period 20 along x and its
// complementary Gray code: the `gray-x` standard sequence with N steps.
Sequence gray_x(int steps, Size projector) {
    PhaseBlock phase;
    phase.axis = Axis::x;
    phase.period = 20;
    phase.steps = steps;
    GrayBlock gray;
    gray.axis = Axis::x;
    gray.period = 20;
    gray.bits = gray_bits_needed(20, projector.width);
    gray.complementary = true;
    return {WhiteBlock{}, BlackBlock{}, phase, gray};
}

// Renders `sequence` through `lut` (none: the drive levels as computed) and decodes it.
DecodeResult capture_and_decode(const sim::Renderer& renderer, const Sequence& sequence,
                                const GammaLut* lut, std::uint64_t seed) {
    const sim::Rig& rig = renderer.rig();
    const auto patterns = render_sequence(sequence, rig.projector_size, lut);
    CaptureSet set;
    set.manifest.camera = rig.camera_size;
    set.manifest.projector = rig.projector_size;
    set.manifest.sequence = sequence;
    for (std::size_t k = 0; k < patterns.size(); ++k) {
        set.manifest.frames.push_back(std::to_string(k) + ".png");
        set.frames.push_back(renderer.render(patterns[k], sim::Renderer::frame_seed(seed, int(k))));
    }
    return decode(set);
}

ResponseRamp render_ramp(const sim::Renderer& renderer, std::uint64_t seed) {
    ResponseRamp ramp;
    ramp.levels = standard_ramp_levels();
    for (std::size_t k = 0; k < ramp.levels.size(); ++k)
        ramp.frames.push_back(
            renderer.render(ramp_pattern(ramp.levels[k], renderer.rig().projector_size),
                            sim::Renderer::frame_seed(seed, int(k))));
    return ramp;
}

// Decoded projector x against the truth (projector pixels) over the pixels
// valid in every result given and with a true coordinate: the RMS error, and
// the RMS of its phase-locked part (the mean error per 1/40 of the fringe
// period, about the overall mean), which is what a projector's curve leaves
// (harmonics aliased onto the phase) and noise averages out of.
struct CoordinateError {
    double rms = 0;
    double phase_locked = 0;
    std::size_t pixels = 0;
};

CoordinateError coordinate_error(const DecodeResult& d, const std::vector<const DecodeResult*>& all,
                                 const Image<float>& truth, double period) {
    constexpr int kBins = 40;
    std::vector<double> bin_sum(kBins, 0.0);
    std::vector<std::size_t> bin_count(kBins, 0);
    double sum = 0, sum2 = 0;
    CoordinateError r;
    for (std::size_t i = 0; i < d.mask.pixel_count(); ++i) {
        const double t = double(truth.data()[2 * i]);
        bool valid = std::isfinite(t);
        for (const DecodeResult* other : all)
            valid = valid && (other->mask.data()[i] & kDecodeValid);
        if (!valid)
            continue;
        const double e = double(d.proj_x.data()[i]) - t;
        const double fraction = t / period - std::floor(t / period);
        const auto bin = std::min(kBins - 1, static_cast<int>(fraction * kBins));
        bin_sum[std::size_t(bin)] += e;
        ++bin_count[std::size_t(bin)];
        sum += e;
        sum2 += e * e;
        ++r.pixels;
    }
    if (r.pixels == 0)
        return r;
    const double mean = sum / double(r.pixels);
    r.rms = std::sqrt(sum2 / double(r.pixels));
    double ripple2 = 0;
    for (int b = 0; b < kBins; ++b) {
        const double m = bin_sum[std::size_t(b)] / double(bin_count[std::size_t(b)]) - mean;
        ripple2 += m * m;
    }
    r.phase_locked = std::sqrt(ripple2 / kBins);
    return r;
}

} // namespace

TEST(ResponseCompensation, MeasuredResponseMakesFewStepsAsGoodAsALinearProjector) {
    const sim::Rig gamma_rig = sim::load_rig(sim::effects_rig_path()).binned_camera(4);
    ASSERT_EQ(gamma_rig.projector_optics.gamma, 2.2);
    sim::Rig linear_rig = gamma_rig;
    linear_rig.projector_optics.gamma = 1.0;
    const sim::Scene scene = sim::named_scene("plane");
    const sim::Renderer gamma_scanner(gamma_rig, scene);
    const sim::Renderer linear_scanner(linear_rig, scene);
    const Image<float>& truth = gamma_scanner.truth_projector();

    // The device's calibration step: the ramp on the board, fitted.
    const ProjectorResponse response = fit_projector_response(render_ramp(gamma_scanner, 77));
    double worst = 0;
    for (std::size_t k = 0; k < response.levels.size(); ++k) {
        const double true_light = std::pow(response.levels[k] / 255.0, 2.2);
        worst = std::max(worst, std::abs(response.emitted[k] - true_light));
    }
    std::printf("fitted response from %zu pixels: worst level off the rig's (l/255)^2.2 by %.5f\n",
                response.pixels_used, worst);
    EXPECT_GT(response.pixels_used, gamma_rig.camera_size.area() * 9 / 10);
    EXPECT_LT(worst, 0.002);
    const GammaLut linearised = GammaLut::from_response(response, 1.0);
    const GammaLut squared = GammaLut::from_response(response, 2.0);

    for (const int steps : {3, 4, 8}) {
        const Sequence sequence = gray_x(steps, gamma_rig.projector_size);
        const double emitted_gamma = compensation_emitted_gamma(sequence);
        EXPECT_EQ(emitted_gamma, steps == 3 ? 1.0 : 2.0);
        const GammaLut& lut = emitted_gamma == 1.0 ? linearised : squared;
        const std::uint64_t seed = 1000 + std::uint64_t(steps);
        const DecodeResult linear = capture_and_decode(linear_scanner, sequence, nullptr, seed);
        const DecodeResult raw = capture_and_decode(gamma_scanner, sequence, nullptr, seed);
        const DecodeResult compensated = capture_and_decode(gamma_scanner, sequence, &lut, seed);
        const DecodeResult inverse = capture_and_decode(gamma_scanner, sequence, &linearised, seed);
        const std::vector<const DecodeResult*> all = {&linear, &raw, &compensated, &inverse};
        const CoordinateError e_lin = coordinate_error(linear, all, truth, 20);
        const CoordinateError e_raw = coordinate_error(raw, all, truth, 20);
        const CoordinateError e_comp = coordinate_error(compensated, all, truth, 20);
        const CoordinateError e_inv = coordinate_error(inverse, all, truth, 20);
        std::printf(
            "%d steps, %zu pixels: projector x error vs truth, RMS (phase-locked part), px:\n"
            "  linear projector          %.4f (%.4f)\n"
            "  gamma 2.2 as is           %.4f (%.4f)  %.2fx linear\n"
            "  through the response, emitted light v^%g  %.4f (%.4f)  %.2fx linear\n"
            "  through its inverse (v^1) %.4f (%.4f)  %.2fx linear\n",
            steps, e_lin.pixels, e_lin.rms, e_lin.phase_locked, e_raw.rms, e_raw.phase_locked,
            e_raw.rms / e_lin.rms, emitted_gamma, e_comp.rms, e_comp.phase_locked,
            e_comp.rms / e_lin.rms, e_inv.rms, e_inv.phase_locked, e_inv.rms / e_lin.rms);
        ASSERT_GT(e_lin.pixels, gamma_rig.camera_size.area() * 8 / 10);
        if (steps < 8) {
            EXPECT_LE(e_comp.rms, 1.3 * e_lin.rms) << steps << " steps";
            EXPECT_LE(e_inv.rms, 1.3 * e_lin.rms) << steps << " steps";
            // What the response leaves in the phase: 0.4 px (3 steps: the
            // curve's second harmonic) and 0.02 px (4 steps: its small third)
            // as is; compensated, what 8-bit drive levels leave (the
            // response's steps near full light are 2.2/255 of the light
            // against 1/255 on a linear projector), a few thousandths.
            EXPECT_LT(e_comp.phase_locked, 0.01) << steps << " steps";
            EXPECT_GT(e_raw.phase_locked, 3 * e_comp.phase_locked) << steps << " steps";
        }
        if (steps == 3) {
            EXPECT_GT(e_raw.rms, 2.0 * e_lin.rms) << "gamma made no error?";
        }
        if (steps == 8) {
            // Today's path: 8 steps cancel the curve's harmonics up to the
            // 6th, and gamma-2.2 fringes carry nearly the linear fringe's
            // amplitude in 28 % less light (less shot noise): the inverse
            // (v^1) is 12 % worse here. Squared fringes carry the full
            // amplitude in 25 % less light; the 8-bit drive's coarser steps
            // add about 0.004 px in quadrature (1 %).
            EXPECT_LE(e_comp.rms, 1.02 * e_raw.rms);
        }
    }
}
