// The capture-set format's pattern blocks (fpp/pattern_block.hpp): the frames
// each block occupies (every kind and phase shifting; Gray planes with and
// without complementary and inverse frames), a sequence's total, and the
// spec's pattern names.

#include "fpp/pattern_block.hpp"

#include <gtest/gtest.h>

namespace {

using namespace fpp;

PhaseBlock phase(int steps, PhaseShifting shifting = PhaseShifting::standard,
                 int carrier_steps = 0) {
    PhaseBlock b;
    b.period = 32;
    b.steps = steps;
    b.shifting = shifting;
    b.carrier_steps = carrier_steps;
    return b;
}

GrayBlock gray(int bits, bool complementary, bool inverse) {
    GrayBlock b;
    b.period = 32;
    b.bits = bits;
    b.complementary = complementary;
    b.inverse = inverse;
    return b;
}

TEST(PatternBlock, FramesOfEachKind) {
    EXPECT_EQ(frame_count(PatternBlock{WhiteBlock{}}), 1);
    EXPECT_EQ(frame_count(PatternBlock{BlackBlock{}}), 1);
    EXPECT_EQ(frame_count(PatternBlock{CenterlineBlock{}}), 1);
    MicroPhaseBlock micro;
    micro.periods = {20.0, 20.5, 21.0, 21.5, 22.0};
    EXPECT_EQ(frame_count(PatternBlock{micro}), 7); // F + 2
    micro.periods = {20.0, 21.0};
    EXPECT_EQ(frame_count(PatternBlock{micro}), 4);
}

TEST(PatternBlock, PhaseFramesFollowTheShifting) {
    EXPECT_EQ(frame_count(PatternBlock{phase(3)}), 3);
    EXPECT_EQ(frame_count(PatternBlock{phase(12)}), 12);
    // 2+1: sin, cos, flat, whatever `steps` says.
    EXPECT_EQ(frame_count(PatternBlock{phase(3, PhaseShifting::two_plus_one)}), 3);
    // Modulated: every shift times every carrier shift.
    EXPECT_EQ(frame_count(PatternBlock{phase(4, PhaseShifting::modulated, 3)}), 12);
    EXPECT_EQ(frame_count(PatternBlock{phase(5, PhaseShifting::modulated, 4)}), 20);
}

TEST(PatternBlock, GrayPlanesWithComplementaryAndInverseFrames) {
    EXPECT_EQ(frame_count(PatternBlock{gray(5, false, false)}), 5);
    EXPECT_EQ(frame_count(PatternBlock{gray(5, true, false)}), 6);  // one more plane
    EXPECT_EQ(frame_count(PatternBlock{gray(5, false, true)}), 10); // each plane inverted too
    EXPECT_EQ(frame_count(PatternBlock{gray(5, true, true)}), 12);
    // n-ary digits, digit order and offset change no frame count.
    GrayBlock ternary = gray(4, false, false);
    ternary.levels = 3;
    ternary.order = DigitOrder::lsb_first;
    ternary.offset = 16;
    EXPECT_EQ(frame_count(PatternBlock{ternary}), 4);
}

TEST(PatternBlock, ASequencesFramesAreItsBlocksFramesInOrder) {
    const Sequence empty;
    EXPECT_EQ(frame_count(empty), 0);
    const Sequence sequence{WhiteBlock{},
                            BlackBlock{},
                            phase(4),
                            gray(6, true, false),
                            phase(3, PhaseShifting::two_plus_one),
                            CenterlineBlock{}};
    EXPECT_EQ(frame_count(sequence), 1 + 1 + 4 + 7 + 3 + 1);
}

TEST(PatternBlock, SpecNamesOfTheBlocks) {
    EXPECT_EQ(pattern_name(WhiteBlock{}), "white");
    EXPECT_EQ(pattern_name(BlackBlock{}), "black");
    EXPECT_EQ(pattern_name(phase(4)), "phase");
    EXPECT_EQ(pattern_name(phase(4, PhaseShifting::modulated, 3)), "phase");
    EXPECT_EQ(pattern_name(gray(5, true, true)), "gray");
    EXPECT_EQ(pattern_name(CenterlineBlock{}), "centerline");
    EXPECT_EQ(pattern_name(MicroPhaseBlock{}), "micro_phase");
}

TEST(PatternBlock, BlocksCompareByEveryField) {
    EXPECT_EQ(phase(4), phase(4));
    PhaseBlock other = phase(4);
    other.phase_offset = 0.5;
    EXPECT_NE(phase(4), other);
    GrayBlock wrapped = gray(5, false, false);
    wrapped.wrap = true;
    EXPECT_NE(gray(5, false, false), wrapped);
    EXPECT_EQ(PatternBlock{WhiteBlock{}}, PatternBlock{WhiteBlock{}});
    EXPECT_NE(PatternBlock{WhiteBlock{}}, PatternBlock{BlackBlock{}});
}

} // namespace
