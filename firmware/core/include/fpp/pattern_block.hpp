#pragma once
// The pattern blocks of the capture-set format fpp-capture/1
// (firmware/core/formats/capture-set.md). A sequence is a list of blocks in capture order.

#include <string>
#include <variant>
#include <vector>

namespace fpp {

enum class Axis { x, y };

inline const char* to_string(Axis a) { return a == Axis::x ? "x" : "y"; }

// Projector full on (texture image): 1 frame.
struct WhiteBlock {
    friend bool operator==(const WhiteBlock&, const WhiteBlock&) = default;
};
// Projector full off: 1 frame.
struct BlackBlock {
    friend bool operator==(const BlackBlock&, const BlackBlock&) = default;
};
// Phase shifting: `steps` frames,
// I_k(p) = 1/2 + 1/2 cos(2 pi p / period + phase_offset + shift_sign 2 pi k / steps).
struct PhaseBlock {
    Axis axis = Axis::x;
    double period = 0;       // projector pixels per fringe period
    int steps = 0;           // N >= 3
    int shift_sign = 1;      // +1 or -1
    double phase_offset = 0; // radians
    friend bool operator==(const PhaseBlock&, const PhaseBlock&) = default;
};
// Gray-code bit planes, MSB first (see spec for complementary and inverse).
struct GrayBlock {
    Axis axis = Axis::x;
    double period = 0; // the phase block's period that it indexes
    int bits = 0;
    bool complementary = false;
    bool inverse = false;
    friend bool operator==(const GrayBlock&, const GrayBlock&) = default;
};
// One bright line at `position` of width `width` (projector pixels): 1 frame.
struct CenterlineBlock {
    Axis axis = Axis::x;
    double position = 0;
    double width = 1;
    friend bool operator==(const CenterlineBlock&, const CenterlineBlock&) = default;
};

using PatternBlock = std::variant<WhiteBlock, BlackBlock, PhaseBlock, GrayBlock, CenterlineBlock>;
using Sequence = std::vector<PatternBlock>;

// Frames that one block occupies in the capture.
int frame_count(const PatternBlock& block);
// Frames of the whole sequence.
int frame_count(const Sequence& sequence);
// The spec's pattern name: "white", "black", "phase", "gray", "centerline".
std::string pattern_name(const PatternBlock& block);

} // namespace fpp
