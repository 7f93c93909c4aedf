#pragma once
// Does a decoded coordinate field agree with itself? A wrong description of
// a capture (the shift direction reversed, a phase offset off by half a
// turn, a code's offset left out) still "decodes" nearly every pixel: the
// unwrapping's checks accept coordinates that are half a period or a whole
// one off. Over smooth surfaces it leaves marks a correct description does
// not, read from the decoded coordinate alone, along camera rows for x (and
// columns for y):
//   - against the trend: the coordinate steps one way from pixel to pixel
//     and the other way over a period and a half (the phase runs backwards
//     inside each period while the cue counts the periods forwards): the
//     phase's shift direction (shift_sign) is wrong;
//   - quantised jumps: between two smoothly stepping sides, a step of half
//     or a whole period more than its neighbours', about once or twice per
//     period (the phase and its cue disagree about where periods begin): a
//     phase offset, or the code's offset, is wrong.
// A correct decode has neither, beyond depth edges and unwrapping errors
// (a jump across a depth edge is of any size, and only a share of them
// lands near half or a whole period). Only axes whose coordinate joins a
// phase to a cue are checked (phase + code, several phase periods); a
// code-only axis, micro phase shifting and a single phase period are not.
//
// Counted on smooth pixels: the four row steps around the pixel within a
// tenth of a period of their median. A jump: the step after the pixel
// differs from the median of the three others (themselves within a tenth of
// a period, less than a quarter period each) by 0.35..0.65 or 0.85..1.15
// periods. The trend: the coordinate's change over 1.5 periods (in camera
// pixels, from the median step) either side.

#include "fpp/decoder.hpp"
#include "fpp/pattern_block.hpp"

#include <cstddef>
#include <string>

namespace fpp {

struct AxisConsistency {
    bool checked = false;     // the axis joins a phase to a cue (see above)
    int phase_block = -1;     // index in the sequence of its finest phase block
    double period = 0;        // that block's period, projector px
    double camera_period = 0; // the period in camera px along the lines (median step)
    std::size_t smooth = 0;   // smooth pixels
    std::size_t against = 0;  // smooth pixels stepping against the trend
    std::size_t jumps = 0;    // quantised jumps between smooth sides
    double against_fraction() const { return smooth ? double(against) / double(smooth) : 0.0; }
    // Jumps per period travelled along the smooth runs (a wrong description:
    // about 1 to 2; a correct one: about 0).
    double jumps_per_period() const {
        return smooth && camera_period > 0 ? double(jumps) / double(smooth) * camera_period : 0.0;
    }
};

struct DecodeConsistency {
    AxisConsistency axis[2]; // x, y
    bool inconsistent = false;
    // What was measured and the field it points at; empty when consistent.
    std::string message;
};

// Thresholds: an axis is inconsistent when at least kMinSmooth pixels are
// smooth and more than kMaxAgainst of them step against the trend, or the
// jumps exceed kMaxJumpsPerPeriod.
inline constexpr std::size_t kConsistencyMinSmooth = 2000;
inline constexpr double kConsistencyMaxAgainst = 0.25;
inline constexpr double kConsistencyMaxJumpsPerPeriod = 0.3;

DecodeConsistency check_decode_consistency(const DecodeResult& result, const Sequence& sequence);

} // namespace fpp
