// The diagnosis of failed decodes (fpp/decode_diagnosis.hpp), its parts that
// need no capture model: the frames' full scale (the lit floor's reference)
// from their depth and bits in use, borrowed frames giving the same figure,
// and no trial run for a decode that is not suspect. (Diagnoses of wrong
// capture descriptions: test_decode_report.cpp, DecodeDiagnosis.)

#include "fpp/capture_set.hpp"
#include "fpp/decode_diagnosis.hpp"
#include "fpp/decode_report.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace {

using namespace fpp;

constexpr Size kCamera{8, 6};

Frame frame16(std::uint16_t fill, std::uint16_t largest, int significant_bits = 0) {
    Frame f;
    f.bit_depth = 16;
    f.significant_bits = significant_bits;
    f.u16 = Image<std::uint16_t>(kCamera, 1, fill);
    f.u16.at(5, 4) = largest;
    return f;
}

Frame frame8(std::uint8_t fill) {
    Frame f;
    f.u8 = Image<std::uint8_t>(kCamera, 1, fill);
    return f;
}

// A set built by hand (no reader set the frames' bits in use).
CaptureSet set_of(std::vector<Frame> frames) {
    CaptureSet set;
    set.folder = "hand-made";
    set.manifest.camera = kCamera;
    set.manifest.projector = {64, 48};
    for (std::size_t i = 0; i < frames.size(); ++i)
        set.manifest.frames.push_back(std::to_string(i) + ".png");
    set.frames = std::move(frames);
    return set;
}

// Three frames of a phase block, as make_capture_set checks and completes them.
CaptureSet checked_set(std::uint16_t largest) {
    CaptureManifest m;
    m.camera = kCamera;
    m.projector = {64, 48};
    PhaseBlock p;
    p.period = 64;
    p.steps = 3;
    m.sequence = {p};
    m.frames = {"0.png", "1.png", "2.png"};
    return make_capture_set("checked", m,
                            {frame16(100, 200), frame16(100, largest), frame16(100, 300)});
}

TEST(DecodeDiagnosis, FullScaleOfEightBitFramesIsTheirContainers) {
    EXPECT_EQ(frames_full_scale(set_of({frame8(3), frame8(10)})), 255.0);
    EXPECT_EQ(frames_full_scale(set_of({})), 255.0); // no frames: 8-bit
}

TEST(DecodeDiagnosis, FullScaleOfSixteenBitFramesFollowsTheBitsInUse) {
    // Known bits in use: their full scale, whatever the samples.
    EXPECT_EQ(frames_full_scale(set_of({frame16(10, 20, 12)})), 4095.0);
    EXPECT_EQ(frames_full_scale(set_of({frame16(10, 20, 10)})), 1023.0);
    // Unknown: the bits the largest sample of any frame needs, at least 8.
    EXPECT_EQ(frames_full_scale(set_of({frame16(10, 3000)})), 4095.0);
    EXPECT_EQ(frames_full_scale(set_of({frame16(10, 20), frame16(10, 4096)})), 8191.0);
    EXPECT_EQ(frames_full_scale(set_of({frame16(10, 100)})), 255.0);
    EXPECT_EQ(frames_full_scale(set_of({frame16(10, 256)})), 511.0);
    EXPECT_EQ(frames_full_scale(set_of({frame16(10, 65535)})), 65535.0);
}

TEST(DecodeDiagnosis, FullScaleOfACheckedSetIsItsBitsInUse) {
    // make_capture_set finds 14 bits in use for a largest value of 5000 (of
    // 9, 10, 12, 14, 16): that full scale, not 13 bits' 8191.
    const CaptureSet set = checked_set(5000);
    ASSERT_EQ(set.bits_in_use, 14);
    EXPECT_EQ(frames_full_scale(set), 16383.0);
    EXPECT_EQ(frames_full_scale(checked_set(3000)), 4095.0);
    EXPECT_EQ(frames_full_scale(checked_set(400)), 511.0);
}

TEST(DecodeDiagnosis, BorrowedFramesGiveTheSameFullScale) {
    for (const CaptureSet& set : {set_of({frame16(10, 3000)}), set_of({frame8(40)}),
                                  set_of({frame16(1, 7, 16)}), checked_set(5000)})
        EXPECT_EQ(frames_full_scale(view_of(set)), frames_full_scale(set));
}

TEST(DecodeDiagnosis, ADecodeThatIsNotSuspectRunsNoTrial) {
    const CaptureSet set = checked_set(3000);
    DecodeResult result; // not read when the statistics are not suspect
    DecodeStatistics stats;
    stats.pixels = 200;
    stats.lit = 100;
    stats.decoded = 95; // 95 % of the lit pixels: not suspect
    const DecodeDiagnosis d = diagnose_decode(set, result, stats, {});
    EXPECT_FALSE(d.failed);
    EXPECT_EQ(d.message, "");
    EXPECT_TRUE(d.trials.empty());
    EXPECT_EQ(d.best_trial, -1);
    EXPECT_EQ(d.bits_in_use, 0);
    EXPECT_EQ(d.bits_declared, 0);
}

TEST(DecodeDiagnosis, NearlyNothingDecodedHasFailedEvenWithoutFramesToTry) {
    DecodeStatistics stats;
    stats.pixels = 200;
    stats.lit = 100;
    stats.decoded = 5; // 5 % of the lit pixels
    const DecodeDiagnosis d = diagnose_decode(set_of({}), DecodeResult{}, stats, {});
    EXPECT_TRUE(d.failed);
    EXPECT_TRUE(d.trials.empty());
    EXPECT_EQ(d.message, "");
    // Lit pixels under 1 % of the image: failed too.
    stats.pixels = 20000;
    stats.decoded = 100;
    EXPECT_TRUE(diagnose_decode(set_of({}), DecodeResult{}, stats, {}).failed);
}

} // namespace
