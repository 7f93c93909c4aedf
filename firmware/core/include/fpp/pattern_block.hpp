#pragma once
// The pattern blocks of the capture-set format (fpp-capture/1 and /2,
// firmware/core/formats/capture-set.md). A sequence is a list of blocks in
// capture order. Fields marked "v2" exist only in fpp-capture/2 files; their
// defaults are what a version-1 file means.

#include "fpp/enum_names.hpp"

#include <string>
#include <variant>
#include <vector>

namespace fpp {

enum class Axis { x, y };
inline constexpr EnumName<Axis> kAxisNames[] = {{Axis::x, "x"}, {Axis::y, "y"}};

inline const char* to_string(Axis a) {
    return name_of(kAxisNames, a, "y");
}

// Projector full on (texture image): 1 frame.
struct WhiteBlock {
    friend bool operator==(const WhiteBlock&, const WhiteBlock&) = default;
};
// Projector full off: 1 frame.
struct BlackBlock {
    friend bool operator==(const BlackBlock&, const BlackBlock&) = default;
};
// How a phase block's frames carry the phase (v2; the spec gives each formula).
enum class PhaseShifting {
    standard,     // `steps` frames shifted by 2 pi k / steps
    two_plus_one, // 3 frames: sin, cos, flat (Zhang and Yau's 2+1); steps == 3
    modulated,    // steps x carrier_steps frames: each phase shift multiplied by a
                  // carrier across the other axis, shifted carrier_steps times
                  // (modulated phase shifting, Chen et al. 2008)
};

inline constexpr EnumName<PhaseShifting> kPhaseShiftingNames[] = {
    {PhaseShifting::standard, "standard"},
    {PhaseShifting::two_plus_one, "two_plus_one"},
    {PhaseShifting::modulated, "modulated"},
};

// The spec's name: "standard", "two_plus_one", "modulated".
inline const char* to_string(PhaseShifting s) {
    return name_of(kPhaseShiftingNames, s, "standard");
}

// Phase shifting: `steps` frames (standard),
// I_k(p) = 1/2 + 1/2 cos(2 pi p / period + phase_offset + shift_sign 2 pi k / steps).
struct PhaseBlock {
    Axis axis = Axis::x;
    double period = 0;       // projector pixels per fringe period (v2: may be written
                             // as a ratio "1920/58" or as `fringes` across the axis)
    int steps = 0;           // N >= 3
    int shift_sign = 1;      // +1 or -1
    double phase_offset = 0; // radians
    PhaseShifting shifting = PhaseShifting::standard; // v2
    double carrier_period = 0; // modulated only: carrier period, projector pixels of the other axis
    int carrier_steps = 0;     // modulated only: carrier shifts (>= 3)
    friend bool operator==(const PhaseBlock&, const PhaseBlock&) = default;
};

// Micro phase shifting (v2; Gupta and Nayar 2012): F >= 2 closely spaced
// periods in F + 2 frames; the first period shifted three times, each other
// period shown once. Decoded with no other cue (see the spec).
struct MicroPhaseBlock {
    Axis axis = Axis::x;
    std::vector<double> periods; // projector pixels, F >= 2
    int shift_sign = 1;
    double phase_offset = 0; // radians, added to every frame
    // Radians added to frame 1 + f (period P_f, f = 2 .. F) on top of
    // phase_offset: empty (all 0) or one entry per period after the first
    // (SLStudio's micro codec inverts every other one: pi).
    std::vector<double> extra_phase_offsets;
    friend bool operator==(const MicroPhaseBlock&, const MicroPhaseBlock&) = default;
};

enum class CodeKind { gray, binary };           // v2: binary = natural binary
enum class DigitOrder { msb_first, lsb_first }; // v2
inline constexpr EnumName<CodeKind> kCodeKindNames[] = {{CodeKind::gray, "gray"},
                                                        {CodeKind::binary, "binary"}};
inline constexpr EnumName<DigitOrder> kDigitOrderNames[] = {{DigitOrder::msb_first, "msb_first"},
                                                            {DigitOrder::lsb_first, "lsb_first"}};

// Code planes (Gray by default), MSB first (see the spec for complementary,
// inverse, and the v2 fields). A block whose period matches a phase block on
// its axis indexes that block's periods; in v2 a block with no such phase
// block codes the axis by itself (code-only sequences).
struct GrayBlock {
    Axis axis = Axis::x;
    double period = 0; // projector pixels per code step
    int bits = 0;      // code digits (planes without inverse or complementary)
    bool complementary = false;
    bool inverse = false;
    CodeKind code = CodeKind::gray;           // v2
    int levels = 2;                           // v2: intensity levels per digit (n-ary)
    DigitOrder order = DigitOrder::msb_first; // v2
    double offset = 0; // v2: projector pixels; code step n covers [offset + n period, ...)
    // v2: the code may number one step fewer than the projector touches, its
    // last step showing the first step's code again (SLMaster's shift-Gray);
    // only for a block that indexes a phase block, which tells the two apart.
    bool wrap = false;
    friend bool operator==(const GrayBlock&, const GrayBlock&) = default;
};
// One bright line at `position` of width `width` (projector pixels): 1 frame.
struct CenterlineBlock {
    Axis axis = Axis::x;
    double position = 0;
    double width = 1;
    friend bool operator==(const CenterlineBlock&, const CenterlineBlock&) = default;
};

using PatternBlock =
    std::variant<WhiteBlock, BlackBlock, PhaseBlock, GrayBlock, CenterlineBlock, MicroPhaseBlock>;
using Sequence = std::vector<PatternBlock>;

// Frames that one block occupies in the capture.
int frame_count(const PatternBlock& block);
// Frames of the whole sequence.
int frame_count(const Sequence& sequence);
// The spec's pattern name: "white", "black", "phase", "gray", "centerline",
// "micro_phase".
std::string pattern_name(const PatternBlock& block);

} // namespace fpp
