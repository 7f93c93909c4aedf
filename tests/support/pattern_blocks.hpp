#pragma once
// Pattern blocks built in one call, for tests that list many sequences.

#include "fpp/pattern_block.hpp"

namespace fpp::test {

inline PhaseBlock phase(Axis axis, double period, int steps, int sign = 1, double offset = 0) {
    PhaseBlock b;
    b.axis = axis;
    b.period = period;
    b.steps = steps;
    b.shift_sign = sign;
    b.phase_offset = offset;
    return b;
}

inline GrayBlock gray(Axis axis, double period, int bits, bool complementary,
                      bool inverse = false) {
    GrayBlock g;
    g.axis = axis;
    g.period = period;
    g.bits = bits;
    g.complementary = complementary;
    g.inverse = inverse;
    return g;
}

} // namespace fpp::test
