// Phase sums for every number of steps: blocks of up to 16 steps are summed by
// weight class (integer sums of the frames sharing a weight), longer ones frame
// by frame. Both must give the analytic phase, modulation and mean, and the
// streaming decoder the batch bytes.

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/sequences.hpp"

#include "../../../firmware/core/src/decode_plan.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

constexpr double kPi = std::numbers::pi;

struct Truth {
    fpp::Image<float> p, a, b; // projector x, mean, modulation (DN)
};

// One phase block covering the projector (direct method), frames computed per
// pixel from the pattern formula, quantised to the frame depth.
fpp::CaptureSet phase_capture(int steps, int sign, double offset, int depth, Truth& truth) {
    const fpp::Size camera{64, 40};
    const double period = 512;
    fpp::PhaseBlock block;
    block.axis = fpp::Axis::x;
    block.period = period;
    block.steps = steps;
    block.shift_sign = sign;
    block.phase_offset = offset;
    fpp::CaptureSet set;
    set.manifest.camera = camera;
    set.manifest.projector = {512, 256};
    set.manifest.sequence = {block};
    const double scale = depth == 8 ? 1.0 / 256.0 : 1.0;
    truth.p = fpp::Image<float>(camera);
    truth.a = fpp::Image<float>(camera);
    truth.b = fpp::Image<float>(camera);
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            truth.p.at(x, y) = static_cast<float>(3.0 + x * 7.6 + y * 0.3);
            truth.a.at(x, y) = static_cast<float>((30000 + 60 * y) * scale);
            truth.b.at(x, y) = static_cast<float>((20000 - 90 * x) * scale);
        }
    for (int k = 0; k < steps; ++k) {
        fpp::Frame f;
        f.bit_depth = depth;
        if (depth == 8)
            f.u8 = fpp::Image<std::uint8_t>(camera);
        else
            f.u16 = fpp::Image<std::uint16_t>(camera);
        for (int y = 0; y < camera.height; ++y)
            for (int x = 0; x < camera.width; ++x) {
                const double phi = 2 * kPi * double(truth.p.at(x, y)) / period + offset +
                                   sign * 2 * kPi * k / steps;
                const long v = std::lround(double(truth.a.at(x, y)) +
                                           double(truth.b.at(x, y)) * std::cos(phi));
                if (depth == 8)
                    f.u8.at(x, y) = static_cast<std::uint8_t>(v);
                else
                    f.u16.at(x, y) = static_cast<std::uint16_t>(v);
            }
        set.frames.push_back(std::move(f));
    }
    return set;
}

template <class T> bool same_bytes(const fpp::Image<T>& a, const fpp::Image<T>& b) {
    return a.size() == b.size() && !a.empty() &&
           std::memcmp(a.data(), b.data(), a.pixel_count() * sizeof(T)) == 0;
}

TEST(DecodeSteps, EveryStepCountGivesThePhaseAndStreamsBitIdentically) {
    for (int steps = 3; steps <= 24; ++steps) {
        for (int depth : {16, 8}) {
            const int sign = steps % 2 == 0 ? 1 : -1;
            const double offset = 0.3 * steps;
            Truth truth;
            const fpp::CaptureSet set = phase_capture(steps, sign, offset, depth, truth);
            fpp::DecodeOptions options;
            options.threads = 2;
            const fpp::DecodeResult batch = fpp::decode(set, options);
            ASSERT_EQ(batch.method_x, "direct");
            double max_p = 0, max_a = 0, max_b = 0;
            for (int y = 0; y < set.manifest.camera.height; ++y)
                for (int x = 0; x < set.manifest.camera.width; ++x) {
                    ASSERT_EQ(batch.mask.at(x, y), fpp::kDecodeValid)
                        << steps << " " << x << " " << y;
                    max_p = std::max(
                        max_p, std::abs(double(batch.proj_x.at(x, y)) - double(truth.p.at(x, y))));
                    max_a = std::max(
                        max_a, std::abs(double(batch.mean.at(x, y)) - double(truth.a.at(x, y))));
                    max_b = std::max(max_b, std::abs(double(batch.modulation.at(x, y)) -
                                                     double(truth.b.at(x, y))));
                }
            // Rounding the samples to integers: at 16 bits a phase error of
            // about 4e-5 rad (3e-3 px at period 512), at 8 bits (modulation about
            // 70 DN) up to about 1e-2 rad.
            const double p_limit = depth == 16 ? 0.005 : 1.2;
            EXPECT_LT(max_p, p_limit) << steps << " steps, " << depth << " bit";
            EXPECT_LT(max_a, 0.6) << steps << " steps, " << depth << " bit";
            EXPECT_LT(max_b, 1.0) << steps << " steps, " << depth << " bit";

            fpp::StreamingDecoder decoder(set.manifest.sequence, set.manifest.camera,
                                          set.manifest.projector, options);
            for (const auto& f : set.frames)
                decoder.push(f);
            const fpp::DecodeResult streamed = decoder.finish();
            EXPECT_TRUE(same_bytes(batch.proj_x, streamed.proj_x)) << steps << " " << depth;
            EXPECT_TRUE(same_bytes(batch.modulation, streamed.modulation)) << steps << " " << depth;
            EXPECT_TRUE(same_bytes(batch.mean, streamed.mean)) << steps << " " << depth;
            EXPECT_TRUE(same_bytes(batch.mask, streamed.mask)) << steps << " " << depth;
        }
    }
}

// Saturation is judged on every frame of the block, whichever way it is summed.
TEST(DecodeSteps, SaturationInAnyFrameOfTheBlockIsFlagged) {
    for (int steps : {4, 8, 13, 20}) {
        Truth truth;
        fpp::CaptureSet set = phase_capture(steps, 1, 0.0, 16, truth);
        const int last = steps - 1;
        set.frames[static_cast<std::size_t>(last)].u16.at(10, 7) = 65535;
        set.frames[0].u16.at(20, 9) = 65535;
        const fpp::DecodeResult r = fpp::decode(set);
        EXPECT_TRUE(r.mask.at(10, 7) & fpp::kDecodeSaturated) << steps;
        EXPECT_TRUE(r.mask.at(20, 9) & fpp::kDecodeSaturated) << steps;
        EXPECT_FALSE(r.mask.at(11, 7) & fpp::kDecodeSaturated) << steps;
        EXPECT_TRUE(std::isnan(r.proj_x.at(10, 7))) << steps;
        EXPECT_EQ(r.mask.at(30, 20), fpp::kDecodeValid) << steps;
    }
}

} // namespace

// The streaming decoder spreads a phase block's work over the frames after
// its last one (up to 4), but never past a step that thresholds against the
// block's mean; its frames stay in slots of their own until the last slice.
TEST(DecodePlan, PhaseBlockIsSlicedUntilItsMeanIsRead) {
    const fpp::Size camera{64, 40};
    const fpp::Size projector{1280, 800};
    auto phase_step = [](const fpp::detail::Plan& plan) {
        for (const auto& s : plan.steps)
            if (s.kind == fpp::detail::StepKind::phase_block)
                return s;
        ADD_FAILURE() << "no phase step";
        return fpp::detail::Step{};
    };

    // inverse-gray-x: 8 phase frames (0-7), then Gray planes each followed by
    // its inverse (a plane waits in a slot for its inverse): sliced over
    // frames 7-10, and the planes that wait meanwhile take other slots.
    const auto inverse = fpp::detail::make_plan(fpp::standard_sequence("inverse-gray-x", projector),
                                                camera, projector);
    const fpp::detail::Step sliced = phase_step(inverse);
    EXPECT_EQ(sliced.trigger, 7);
    EXPECT_EQ(sliced.parts, 4);
    std::set<int> block_slots;
    for (int f = 0; f <= 7; ++f) {
        const int slot = inverse.frame_slot[static_cast<std::size_t>(f)];
        EXPECT_GE(slot, 0) << "frame " << f;
        block_slots.insert(slot);
    }
    EXPECT_EQ(block_slots.size(), 8u); // one slot per frame of the block
    int waiting = 0;
    for (int f = 8; f <= 10; ++f) {
        const int slot = inverse.frame_slot[static_cast<std::size_t>(f)];
        waiting += slot >= 0 ? 1 : 0;
        EXPECT_EQ(block_slots.count(slot), 0u)
            << "frame " << f << " overwrites a frame of the block before its last slice";
    }
    EXPECT_GT(waiting, 0);

    // gray-x (white, black, phase frames 2-9, Gray planes against white and
    // black): sliced over frames 9-12.
    const auto gray_x =
        fpp::detail::make_plan(fpp::standard_sequence("gray-x", projector), camera, projector);
    EXPECT_EQ(phase_step(gray_x).trigger, 9);
    EXPECT_EQ(phase_step(gray_x).parts, 4);

    // No white and black frames: the Gray planes (frames 8 on) are
    // thresholded against the phase mean, so the block is decoded whole at
    // its last frame.
    fpp::PhaseBlock phase;
    phase.axis = fpp::Axis::x;
    phase.period = 20;
    phase.steps = 8;
    fpp::GrayBlock gray;
    gray.axis = fpp::Axis::x;
    gray.period = 20;
    gray.bits = fpp::gray_bits_needed(20, projector.width);
    gray.complementary = true;
    const auto mean_read = fpp::detail::make_plan({phase, gray}, camera, projector);
    EXPECT_EQ(phase_step(mean_read).trigger, 7);
    EXPECT_EQ(phase_step(mean_read).parts, 1);

    // A block at the end of the sequence has no frames after it.
    phase.period = 1280;
    const auto last = fpp::detail::make_plan({phase}, camera, projector);
    EXPECT_EQ(phase_step(last).parts, 1);
}

// fpp-capture/2 families: the method each axis gets, the wrapped steps of a
// shifted code, and the refusals that name the block and the reason.
namespace {

fpp::GrayBlock gray_block(double period, int bits) {
    fpp::GrayBlock g;
    g.axis = fpp::Axis::x;
    g.period = period;
    g.bits = bits;
    return g;
}

fpp::PhaseBlock phase_block(double period, int steps) {
    fpp::PhaseBlock p;
    p.axis = fpp::Axis::x;
    p.period = period;
    p.steps = steps;
    return p;
}

std::string method_of(const fpp::Sequence& sequence) {
    return fpp::detail::make_plan(sequence, {64, 40}, {1280, 800}).axes[0].name;
}

std::string refusal(const fpp::Sequence& sequence) {
    try {
        fpp::detail::make_plan(sequence, {64, 40}, {1280, 800});
    } catch (const fpp::InputError& e) {
        return e.what();
    }
    return "accepted";
}

// The file and field of a refusal, for a plan made for `origin`.
std::string refused_field(const fpp::Sequence& sequence, const std::string& origin,
                          fpp::Size projector = {1280, 800}) {
    try {
        fpp::detail::make_plan(sequence, {64, 40}, projector, origin);
    } catch (const fpp::InputError& e) {
        return e.file().string() + " | " + e.field();
    }
    return "accepted";
}

TEST(DecodePlanFamilies, MethodNames) {
    fpp::GrayBlock inverse = gray_block(1.25, 10);
    inverse.inverse = true;
    EXPECT_EQ(method_of({inverse}), "inverse-gray-code");
    fpp::GrayBlock binary = gray_block(1.25, 10);
    binary.code = fpp::CodeKind::binary;
    EXPECT_EQ(method_of({fpp::WhiteBlock{}, fpp::BlackBlock{}, binary}), "binary-code");
    fpp::GrayBlock quaternary = gray_block(1.25, 5);
    quaternary.levels = 4;
    EXPECT_EQ(method_of({fpp::WhiteBlock{}, fpp::BlackBlock{}, quaternary}), "gray-code-4-level");
    fpp::GrayBlock shifted = gray_block(20, 7);
    shifted.offset = 10;
    EXPECT_EQ(method_of({phase_block(20, 4), shifted}), "shifted-gray");
    fpp::PhaseBlock two_plus_one = phase_block(1280.0 / 58.0, 3);
    two_plus_one.shifting = fpp::PhaseShifting::two_plus_one;
    fpp::GrayBlock rational = gray_block(1280.0 / 58.0, 6);
    rational.complementary = true;
    EXPECT_EQ(method_of({two_plus_one, rational}), "complementary-gray");
    fpp::MicroPhaseBlock micro;
    micro.periods = {16, 16.5, 17, 17.5, 18};
    EXPECT_EQ(method_of({micro}), "micro-phase");
}

TEST(DecodePlanFamilies, ShiftedCodeWrapsLeftOfTheOffset) {
    fpp::GrayBlock shifted = gray_block(20, 7);
    shifted.offset = 10;
    const fpp::detail::Plan plan =
        fpp::detail::make_plan({phase_block(20, 4), shifted}, {64, 40}, {1280, 800});
    const auto& table = plan.grays[0].step_of_code;
    ASSERT_EQ(table.size(), 128u);
    // Gray codeword of 127 (pixels 0 .. 9, left of the offset) is 64.
    EXPECT_EQ(table[64], -1.0f);
    EXPECT_EQ(table[0], 0.0f);
    EXPECT_EQ(table[1], 1.0f);
    EXPECT_EQ(table[3], 2.0f);                // Gray 2 = 11b
    EXPECT_EQ(plan.grays[0].max_step, 63.0f); // 10 + 63 * 20 = 1270 < 1279.5
}

TEST(DecodePlanFamilies, RefusalsNameTheBlockAndReason) {
    fpp::MicroPhaseBlock micro;
    micro.periods = {16, 17};
    EXPECT_NE(refusal({micro, gray_block(16, 7)}).find("micro phase shifting codes its axis alone"),
              std::string::npos);
    fpp::GrayBlock quaternary = gray_block(1.25, 5);
    quaternary.levels = 4;
    EXPECT_NE(refusal({quaternary}).find("need white and black frames"), std::string::npos);
    quaternary.inverse = true;
    EXPECT_NE(refusal({quaternary}).find("inverse frames are not defined"), std::string::npos);
    EXPECT_NE(refusal({gray_block(1.25, 10)}).find("gray block 0 (axis x)"), std::string::npos);
    fpp::PhaseBlock two_plus_one = phase_block(1280, 4);
    two_plus_one.shifting = fpp::PhaseShifting::two_plus_one;
    EXPECT_NE(refusal({two_plus_one}).find("2+1 phase shifting has steps 3"), std::string::npos);
    fpp::PhaseBlock modulated = phase_block(1280, 3);
    modulated.shifting = fpp::PhaseShifting::modulated;
    modulated.carrier_period = 8;
    modulated.carrier_steps = 2;
    EXPECT_NE(refusal({modulated}).find("carrier_steps must be in [3, 16]"), std::string::npos);
    fpp::GrayBlock levels = gray_block(1.25, 9);
    levels.levels = 4;
    EXPECT_NE(refusal({fpp::WhiteBlock{}, fpp::BlackBlock{}, levels}).find("at most 65536"),
              std::string::npos);
}

// A refusal names the manifest the plan is for (else the decoder) and the
// field as the capture-set reader does: the block's place in the sequence.
TEST(DecodePlanFamilies, RefusalsNameTheManifestAndTheField) {
    const std::string manifest = "scans/plane/capture.yaml";
    fpp::PhaseBlock two_plus_one = phase_block(1280, 4);
    two_plus_one.shifting = fpp::PhaseShifting::two_plus_one;
    EXPECT_EQ(refused_field({fpp::WhiteBlock{}, two_plus_one}, manifest),
              manifest + " | sequence[1].steps");
    fpp::GrayBlock wrapping = gray_block(40, 5);
    wrapping.complementary = true;
    wrapping.wrap = true;
    EXPECT_EQ(refused_field({phase_block(40, 4), wrapping}, manifest),
              manifest + " | sequence[1].wrap");
    EXPECT_EQ(refused_field({phase_block(20, 8), phase_block(20, 4)}, manifest),
              manifest + " | sequence[1].period");
    EXPECT_EQ(refused_field({phase_block(20, 8), phase_block(22, 8)}, manifest),
              manifest + " | sequence");
    EXPECT_EQ(refused_field({phase_block(1280, 4)}, manifest, {0, 800}), manifest + " | projector");
    try {
        fpp::detail::make_plan({phase_block(20, 8)}, {64, 40}, {1280, 800});
        ADD_FAILURE() << "accepted a phase block without a cue";
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), std::filesystem::path(fpp::kDecoderOrigin));
        EXPECT_EQ(e.field(), "sequence[0].period");
        EXPECT_EQ(
            std::string(e.what()).rfind("decoder: sequence[0].period: cannot decode sequence: "
                                        "the phase block on axis x",
                                        0),
            0u)
            << e.what();
    }
}

} // namespace
