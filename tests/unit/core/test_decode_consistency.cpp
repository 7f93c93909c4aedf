// Whether a decoded coordinate field agrees with itself
// (fpp/decode_consistency.hpp), on coordinate fields written here whose
// counts follow from the rules: a smooth ramp (no marks), a phase running
// backwards inside each period (against the trend: the shift direction), a
// jump of half a period at each period's start (the offsets), which axes
// are checked, too few smooth pixels, and pixels that did not decode.
// (test_decode_consistency_sim.cpp checks it on rendered captures.)

#include "fpp/decode_consistency.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

namespace {

using namespace fpp;

constexpr double kPeriod = 16; // projector px; one projector px per camera px below

// White, then a phase block and a Gray block on `axis` (index 1 and 2).
Sequence phase_and_gray(Axis axis) {
    PhaseBlock p;
    p.axis = axis;
    p.period = kPeriod;
    p.steps = 4;
    GrayBlock g;
    g.axis = axis;
    g.period = kPeriod;
    g.bits = 5;
    return {WhiteBlock{}, p, g};
}

// A result of `lines` lines of `length` pixels along `axis` (rows for x,
// columns for y), the coordinate u(k) at position k of every line, every
// pixel decoded.
DecodeResult field(Axis axis, int length, int lines, const std::function<double(int)>& u) {
    const Size size = axis == Axis::x ? Size{length, lines} : Size{lines, length};
    DecodeResult r;
    r.camera = size;
    Image<float>& coordinate = axis == Axis::x ? r.proj_x : r.proj_y;
    coordinate = Image<float>(size);
    r.mask = Image<std::uint8_t>(size, 1, kDecodeValid);
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x)
            coordinate.at(x, y) = static_cast<float>(u(axis == Axis::x ? x : y));
    return r;
}

double ramp(int k) {
    return k;
}
// Runs backwards inside each period while the periods count forwards.
double backwards(int k) {
    return kPeriod * (k / 16) + 15 - k % 16;
}
// Half a period more at the start of every period.
double half_period_jumps(int k) {
    return k + 0.5 * kPeriod * (k / 16);
}

// Along a line of 400: 396 positions have four steps around them; of them
// 25 periods x 12 keep all four inside one period (the others straddle a
// period's start), and 264 of those lie 24 px (1.5 periods) from both ends.
constexpr int kLength = 400;
constexpr int kLines = 40;

TEST(DecodeConsistency, ASmoothRampHasNoMarks) {
    const DecodeConsistency c =
        check_decode_consistency(field(Axis::x, kLength, kLines, ramp), phase_and_gray(Axis::x));
    const AxisConsistency& x = c.axis[0];
    EXPECT_TRUE(x.checked);
    EXPECT_EQ(x.phase_block, 1);
    EXPECT_EQ(x.period, kPeriod);
    EXPECT_EQ(x.camera_period, 16.0);
    EXPECT_EQ(x.smooth, std::size_t(396 * kLines));
    EXPECT_EQ(x.against, 0u);
    EXPECT_EQ(x.jumps, 0u);
    EXPECT_FALSE(c.axis[1].checked); // the sequence codes no y
    EXPECT_FALSE(c.inconsistent);
    EXPECT_EQ(c.message, "");
}

TEST(DecodeConsistency, PhaseRunningBackwardsInsideThePeriodsPointsAtShiftSign) {
    const DecodeConsistency c = check_decode_consistency(field(Axis::x, kLength, kLines, backwards),
                                                         phase_and_gray(Axis::x));
    const AxisConsistency& x = c.axis[0];
    EXPECT_EQ(x.camera_period, 16.0);
    EXPECT_EQ(x.smooth, std::size_t(300 * kLines));
    EXPECT_EQ(x.against, std::size_t(264 * kLines));
    EXPECT_EQ(x.jumps, 0u);
    EXPECT_DOUBLE_EQ(x.against_fraction(), 0.88);
    EXPECT_TRUE(c.inconsistent);
    EXPECT_EQ(c.message,
              "along x the coordinate steps against its own trend on 88 % of the smooth pixels "
              "(the phase runs backwards inside each period while its cue counts the periods "
              "forwards): check shift_sign of sequence[1]");
}

TEST(DecodeConsistency, HalfPeriodJumpsPointAtThePhaseOffset) {
    const DecodeConsistency c = check_decode_consistency(
        field(Axis::x, kLength, kLines, half_period_jumps), phase_and_gray(Axis::x));
    const AxisConsistency& x = c.axis[0];
    EXPECT_EQ(x.smooth, std::size_t(300 * kLines));
    EXPECT_EQ(x.against, 0u);
    EXPECT_EQ(x.jumps, std::size_t(24 * kLines)); // every period's start inside the line
    EXPECT_DOUBLE_EQ(x.jumps_per_period(), 1.28); // 960 / 12000 x 16
    EXPECT_TRUE(c.inconsistent);
    EXPECT_EQ(c.message,
              "along x the coordinate jumps by half or a whole period between smoothly stepping "
              "pixels 1.28 times per period (a correct description leaves about none: the phase "
              "and its cue disagree about where the periods begin): check phase_offset of "
              "sequence[1], or the offset of the code block");
}

TEST(DecodeConsistency, OnlyJumpsNearHalfOrAWholePeriodCount) {
    // Jumps of 0.25, 0.5, 0.75, 1 and 1.25 periods at each period's start.
    for (const double size : {0.25, 0.5, 0.75, 1.0, 1.25}) {
        const auto u = [size](int k) { return k + size * kPeriod * (k / 16); };
        const DecodeConsistency c =
            check_decode_consistency(field(Axis::x, kLength, kLines, u), phase_and_gray(Axis::x));
        const bool counted = size == 0.5 || size == 1.0;
        EXPECT_EQ(c.axis[0].jumps, counted ? std::size_t(24 * kLines) : 0u) << size;
        EXPECT_EQ(c.inconsistent, counted) << size;
    }
}

TEST(DecodeConsistency, TheYAxisIsReadAlongColumns) {
    const DecodeConsistency c = check_decode_consistency(field(Axis::y, kLength, kLines, backwards),
                                                         phase_and_gray(Axis::y));
    EXPECT_FALSE(c.axis[0].checked);
    const AxisConsistency& y = c.axis[1];
    EXPECT_TRUE(y.checked);
    EXPECT_EQ(y.smooth, std::size_t(300 * kLines));
    EXPECT_EQ(y.against, std::size_t(264 * kLines));
    EXPECT_TRUE(c.inconsistent);
    EXPECT_EQ(c.message.rfind("along y the coordinate steps against its own trend on 88 %", 0), 0u)
        << c.message;
}

TEST(DecodeConsistency, OnlyAPhaseJoinedToACueIsChecked) {
    const DecodeResult r = field(Axis::x, kLength, kLines, backwards);
    PhaseBlock fine;
    fine.period = kPeriod;
    fine.steps = 4;
    PhaseBlock coarse = fine;
    coarse.period = 400;
    GrayBlock code;
    code.period = kPeriod;
    code.bits = 5;
    code.inverse = true;
    MicroPhaseBlock micro;
    micro.periods = {16, 17, 18};
    // Not checked: one phase period alone, a code alone, micro phase shifting.
    for (const Sequence& s : {Sequence{fine}, Sequence{WhiteBlock{}, BlackBlock{}, code},
                              Sequence{PatternBlock{micro}}}) {
        const DecodeConsistency c = check_decode_consistency(r, s);
        EXPECT_FALSE(c.axis[0].checked);
        EXPECT_EQ(c.axis[0].smooth, 0u);
        EXPECT_FALSE(c.inconsistent);
    }
    // Checked: several phase periods (the finest is measured), a phase and a centerline.
    const DecodeConsistency periods = check_decode_consistency(r, {coarse, BlackBlock{}, fine});
    EXPECT_TRUE(periods.axis[0].checked);
    EXPECT_EQ(periods.axis[0].phase_block, 2);
    EXPECT_EQ(periods.axis[0].period, kPeriod);
    EXPECT_TRUE(periods.inconsistent);
    EXPECT_NE(periods.message.find("check shift_sign of sequence[2]"), std::string::npos);
    const DecodeConsistency centerline = check_decode_consistency(r, {fine, CenterlineBlock{}});
    EXPECT_TRUE(centerline.axis[0].checked);
    EXPECT_TRUE(centerline.inconsistent);
}

TEST(DecodeConsistency, TooFewSmoothPixelsAreNotJudged) {
    // 6 lines: 1800 smooth pixels, fewer than kConsistencyMinSmooth.
    const DecodeConsistency c =
        check_decode_consistency(field(Axis::x, kLength, 6, backwards), phase_and_gray(Axis::x));
    EXPECT_EQ(c.axis[0].smooth, 1800u);
    EXPECT_LT(c.axis[0].smooth, kConsistencyMinSmooth);
    EXPECT_EQ(c.axis[0].against, 264u * 6u); // measured all the same
    EXPECT_FALSE(c.inconsistent);
    EXPECT_EQ(c.message, "");
}

TEST(DecodeConsistency, PixelsThatDidNotDecodeAreNotRead) {
    DecodeResult r = field(Axis::x, kLength, kLines, backwards);
    // Every pixel flagged, none valid: nothing smooth, no period found.
    for (std::uint8_t& m : r.mask.storage())
        m = kDecodeUnwrapInconsistent;
    DecodeConsistency c = check_decode_consistency(r, phase_and_gray(Axis::x));
    EXPECT_TRUE(c.axis[0].checked);
    EXPECT_EQ(c.axis[0].smooth, 0u);
    EXPECT_EQ(c.axis[0].camera_period, 0.0);
    EXPECT_FALSE(c.inconsistent);
    // Every other line decoded: half the counts.
    for (int y = 0; y < kLines; y += 2)
        for (int x = 0; x < kLength; ++x)
            r.mask.at(x, y) = kDecodeValid;
    c = check_decode_consistency(r, phase_and_gray(Axis::x));
    EXPECT_EQ(c.axis[0].smooth, std::size_t(300 * kLines / 2));
    EXPECT_EQ(c.axis[0].against, std::size_t(264 * kLines / 2));
    // No coordinate image at all: the axis is planned, not measured.
    r.proj_x = Image<float>();
    c = check_decode_consistency(r, phase_and_gray(Axis::x));
    EXPECT_TRUE(c.axis[0].checked);
    EXPECT_EQ(c.axis[0].smooth, 0u);
    EXPECT_FALSE(c.inconsistent);
}

} // namespace
