// The data-only phase-error correction (DecodeOptions::correct_phase_error,
// fpp/phase_error_correction.hpp) on the virtual scanner: the effects rig
// (projector gamma 2.2, 0.5 % black level, projector and camera defocus,
// shot and read noise), camera binned 4 x 4, against the same rig with a
// linear projector (gamma 1), same noise seed. Sequences as "gray-x"
// (white, black, N-step phase of period 20 + complementary Gray along x)
// with N = 3, 4, 8. Errors are decoded minus true projector column over the
// pixels valid in every decode (without unwrapping errors).
//
// Targets (issue 15, tightened by issue 32): with 3 steps the corrected RMS
// within 1.08x the linear projector's, with 4 steps no worse than the linear
// projector; with 8 steps no worse than uncorrected (1.02x); a linear
// projector left as it is. Measured (figures printed), correction taken at
// each pixel's 3 x 3 stand-in (before: at the decoded fold):
//   composite:      3 steps 7.28x -> 1.02x (1.11x), 4 steps 0.95x -> 0.91x, 8 steps 0.91x
//   inclined plane: 3 steps 10.15x -> 0.93x (1.02x), 4 steps 0.96x -> 0.87x, 8 steps 0.87x
//   fronto-parallel plane: 3 steps 9.63x -> 0.94x (1.03x), 4 steps 0.96x -> 0.87x;
//   8 steps refused (the pixel grid aliases the fringes at harmonic 1: a
//   0.006 px sampling bias cannot be told from an error), so unchanged.
// Below 1x: the stand-in takes the correction at the true fold with a third
// of the pixel's noise, and the gamma's steeper flanks carry less noise.
// The 4-step error under gamma 2.2 is below the noise here (0.02 px RMS;
// blur and noise make the gamma rig's 4-step decode no worse than the
// linear one's); 8 steps leave none to correct.

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/pattern_block.hpp"
#include "fpp/phase_error_correction.hpp"
#include "fpp/sequences.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

namespace {

constexpr double kPeriod = 20.0;
constexpr std::uint64_t kSeed = 23;

fpp::Sequence gray_x(int steps, fpp::Size projector) {
    fpp::PhaseBlock phase;
    phase.axis = fpp::Axis::x;
    phase.period = kPeriod;
    phase.steps = steps;
    fpp::GrayBlock gray;
    gray.axis = fpp::Axis::x;
    gray.period = kPeriod;
    gray.bits = fpp::gray_bits_needed(kPeriod, projector.width);
    gray.complementary = true;
    return {fpp::WhiteBlock{}, fpp::BlackBlock{}, phase, gray};
}

fpp::sim::Rig effects_rig(double gamma) {
    fpp::sim::Rig rig = fpp::sim::load_rig(fpp::sim::effects_rig_path()).binned_camera(4);
    rig.projector_optics.gamma = gamma;
    return rig;
}

fpp::CaptureSet to_capture(const fpp::sim::SimulatedCapture& sim) {
    return fpp::CaptureSet{{}, sim.manifest, sim.frames};
}

fpp::DecodeResult decode_sim(const fpp::sim::SimulatedCapture& sim, bool correct) {
    fpp::DecodeOptions options;
    options.correct_phase_error = correct;
    return fpp::decode(to_capture(sim), options);
}

bool valid(const fpp::DecodeResult& r, std::size_t i) {
    return (r.mask.data()[i] & fpp::kDecodeValid) != 0;
}

// RMS (projector pixels) of decoded minus true x of each result, over the
// pixels valid in all of them with a lit truth, without unwrapping errors.
template <std::size_t N>
std::array<double, N> rms_over_common(const std::array<const fpp::DecodeResult*, N>& results,
                                      const fpp::Image<float>& truth, std::size_t& pixels) {
    std::array<double, N> sum{};
    pixels = 0;
    for (std::size_t i = 0; i < truth.pixel_count(); ++i) {
        const double t = truth.data()[2 * i];
        if (!std::isfinite(t))
            continue;
        std::array<double, N> e{};
        bool ok = true;
        for (std::size_t r = 0; r < N && ok; ++r) {
            ok = valid(*results[r], i);
            e[r] = double(results[r]->proj_x.data()[i]) - t;
            ok = ok && std::abs(e[r]) <= kPeriod / 2;
        }
        if (!ok)
            continue;
        for (std::size_t r = 0; r < N; ++r)
            sum[r] += e[r] * e[r];
        ++pixels;
    }
    for (double& s : sum)
        s = std::sqrt(s / static_cast<double>(pixels));
    return sum;
}

class PhaseErrorCorrectionSim : public ::testing::TestWithParam<std::string> {};

TEST_P(PhaseErrorCorrectionSim, MeetsTheTargetsOfIssue15) {
    const std::string scene_name = GetParam();
    const fpp::sim::Scene scene = fpp::sim::named_scene(scene_name);
    const fpp::sim::Renderer gamma_renderer(effects_rig(2.2), scene);
    const fpp::sim::Renderer linear_renderer(effects_rig(1.0), scene);
    for (const int steps : {3, 4, 8}) {
        SCOPED_TRACE(std::to_string(steps) + " steps on " + scene_name);
        const fpp::Sequence sequence = gray_x(steps, gamma_renderer.rig().projector_size);
        const auto gamma_sim = fpp::sim::simulate(gamma_renderer, sequence, kSeed);
        const auto linear_sim = fpp::sim::simulate(linear_renderer, sequence, kSeed);
        const fpp::DecodeResult raw = decode_sim(gamma_sim, false);
        const fpp::DecodeResult corrected = decode_sim(gamma_sim, true);
        const fpp::DecodeResult linear = decode_sim(linear_sim, false);
        const fpp::DecodeResult linear_corrected = decode_sim(linear_sim, true);
        std::size_t pixels = 0;
        const auto rms = rms_over_common<4>({&raw, &corrected, &linear, &linear_corrected},
                                            gamma_sim.truth_projector, pixels);
        const double raw_ratio = rms[0] / rms[2], corrected_ratio = rms[1] / rms[2];
        std::printf("[ figures  ] %-14s %d steps: RMS vs truth: linear projector %.4f px, gamma "
                    "2.2 %.4f px (%.2fx), corrected %.4f px (%.2fx); linear corrected %.4f px; "
                    "%zu px\n[ figures  ]   gamma: %s\n[ figures  ]   linear: %s\n",
                    scene_name.c_str(), steps, rms[2], rms[0], raw_ratio, rms[1], corrected_ratio,
                    rms[3], pixels, fpp::describe(corrected.phase_correction_x).c_str(),
                    fpp::describe(linear_corrected.phase_correction_x).c_str());
        ASSERT_GT(pixels, 50000u);
        EXPECT_EQ(0, std::memcmp(raw.mask.data(), corrected.mask.data(), raw.mask.pixel_count()));
        if (steps < 8) {
            EXPECT_TRUE(corrected.phase_correction_x.applied)
                << corrected.phase_correction_x.reason;
            EXPECT_LE(corrected_ratio, steps == 3 ? 1.08 : 1.0);
            EXPECT_LE(rms[1], rms[0] * 1.02);
            EXPECT_GT(corrected.phase_correction_x.at_stand_in, 0.9);
        } else {
            EXPECT_LE(rms[1], rms[0] * 1.02);
        }
        if (steps == 3) { // the 3-step gamma error is 7 to 10 times the noise
            EXPECT_GT(raw_ratio, 5.0);
        }
        EXPECT_LE(rms[3], rms[2] * 1.02); // a linear projector is left as it is
    }
}

INSTANTIATE_TEST_SUITE_P(Scenes, PhaseErrorCorrectionSim,
                         ::testing::Values("composite", "inclined-plane", "plane"),
                         [](const auto& param_info) {
                             std::string n = param_info.param;
                             for (char& c : n)
                                 if (c == '-')
                                     c = '_';
                             return n;
                         });

// Rigs the correction was never tuned on (a thin-prism projector lens, a
// decentred projector lens, a camera with a lens defect; each with the
// effects rig's gamma 2.2, blur and noise), 3 steps on the composite scene:
// within 1.08x the same rig with a linear projector. Measured 1.00x, 1.03x,
// 1.04x (at the decoded fold: 1.08x, 1.11x, 1.12x binned 2).
TEST(PhaseErrorCorrectionSimHeldOut, ThreeStepsWithinAFewPercentOfALinearProjector) {
    const fpp::sim::Scene scene = fpp::sim::named_scene("composite");
    for (const char* name :
         {"rig-prism-projector.yaml", "rig-decentred-projector.yaml", "rig-camera-defect.yaml"}) {
        SCOPED_TRACE(name);
        fpp::sim::Rig rig =
            fpp::sim::load_rig(fpp::sim::effects_rig_path().parent_path() / name).binned_camera(4);
        ASSERT_EQ(rig.projector_optics.gamma, 2.2);
        fpp::sim::Rig linear_rig = rig;
        linear_rig.projector_optics.gamma = 1.0;
        const fpp::Sequence sequence = gray_x(3, rig.projector_size);
        const auto gamma_sim = fpp::sim::simulate(rig, scene, sequence, kSeed);
        const auto linear_sim = fpp::sim::simulate(linear_rig, scene, sequence, kSeed);
        const fpp::DecodeResult corrected = decode_sim(gamma_sim, true);
        const fpp::DecodeResult linear = decode_sim(linear_sim, false);
        std::size_t pixels = 0;
        const auto rms =
            rms_over_common<2>({&corrected, &linear}, gamma_sim.truth_projector, pixels);
        std::printf("[ figures  ] %s: linear projector %.4f px, gamma 2.2 corrected %.4f px "
                    "(%.2fx); %s\n",
                    name, rms[1], rms[0], rms[0] / rms[1],
                    fpp::describe(corrected.phase_correction_x).c_str());
        ASSERT_GT(pixels, 50000u);
        ASSERT_TRUE(corrected.phase_correction_x.applied) << corrected.phase_correction_x.reason;
        EXPECT_LE(rms[0], 1.08 * rms[1]);
    }
}

// The streaming decoder with the correction gives the batch result bit for
// bit (the correction is a pass over the finished result in both).
TEST(PhaseErrorCorrectionSimStreaming, BitIdenticalToBatch) {
    const fpp::sim::Rig rig = effects_rig(2.2);
    const auto sim = fpp::sim::simulate(rig, fpp::sim::named_scene("composite"),
                                        gray_x(3, rig.projector_size), kSeed);
    const fpp::CaptureSet set = to_capture(sim);
    fpp::DecodeOptions options;
    options.correct_phase_error = true;
    const fpp::DecodeResult batch = fpp::decode(set, options);
    fpp::StreamingDecoder decoder(set.manifest.sequence, set.manifest.camera,
                                  set.manifest.projector, options);
    for (const auto& f : set.frames)
        decoder.push(f);
    const fpp::DecodeResult streamed = decoder.finish();
    ASSERT_TRUE(batch.phase_correction_x.applied) << batch.phase_correction_x.reason;
    EXPECT_EQ(batch.phase_correction_x.sine, streamed.phase_correction_x.sine);
    EXPECT_EQ(batch.phase_correction_x.cosine, streamed.phase_correction_x.cosine);
    EXPECT_EQ(0, std::memcmp(batch.proj_x.data(), streamed.proj_x.data(),
                             batch.proj_x.pixel_count() * sizeof(float)));
    EXPECT_EQ(0, std::memcmp(batch.mask.data(), streamed.mask.data(), batch.mask.pixel_count()));
}

} // namespace
