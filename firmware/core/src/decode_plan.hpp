#pragma once
// Decoding plan: which blocks a sequence decodes each axis with, and the list
// of steps, each run once the frames it reads have arrived. Both the batch and
// the streaming decoder execute the same steps in the same order, which is
// what makes them bit-identical.

#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace fpp::detail {

enum class UnwrapMethod { direct, multi_period, heterodyne, gray, centerline };

struct PhaseInfo {
    PhaseBlock block;
    int first_frame = 0;
    int axis = 0;             // 0 = x, 1 = y
    // cos(delta_k) and -shift_sign * sin(delta_k), so that
    // theta = atan2(sum sin_w I, sum cos_w I).
    std::vector<float> cos_w;
    std::vector<float> sin_w;
    // Blocks of at most kMaxClassSteps steps sum by weight class
    // (decode_weights.hpp) with these class weights instead of cos_w, sin_w.
    std::vector<float> class_cos_w; // cos(2 pi j / N)
    std::vector<float> class_sin_w; // -shift_sign * sin(2 pi (j + 1) / N)
    float offset_fraction = 0;      // phase_offset / (2 pi)
    bool used = false;
    bool thresholds = false; // a gray or centerline block is thresholded against its mean
    int last_frame() const { return first_frame + block.steps - 1; }
};

enum class GrayThreshold { white_black, inverse, phase_mean };

struct GrayInfo {
    GrayBlock block;
    int first_frame = 0;
    int axis = 0;
    int planes = 0; // bits (+1 if complementary)
    GrayThreshold threshold = GrayThreshold::phase_mean;
    int phase = -1; // index into Plan::phases: the block it indexes (and thresholds against)
};

struct CenterlineInfo {
    CenterlineBlock block;
    int frame = 0;
    int axis = 0;
    int phase = -1; // the phase block it makes absolute (and thresholds against)
};

// One level of a heterodyne chain: wrapped fraction = frac(sum_j coef[j] * phi_j)
// over the axis's phase blocks (AxisPlan::phases order), with this period.
struct HeterodyneLevel {
    double period = 0;
    int coef[3] = {0, 0, 0};
    int single = -1; // index j when the level is phase block j itself, else -1
};

struct AxisPlan {
    bool coded = false;
    UnwrapMethod method = UnwrapMethod::direct;
    std::string name;
    double extent = 0;       // projector pixels along the axis
    std::vector<int> phases; // multi_period: coarse to fine; heterodyne: by period,
                             // ascending; others: the one block
    int report_phase = -1;   // finest block (its B and A go to the result)
    int gray = -1;
    int centerline = -1;
    std::vector<HeterodyneLevel> levels; // heterodyne: root (covers the extent) to finest
};

enum class StepKind {
    phase_block,       // all frames of a phase block -> wrapped fraction, modulation, mean
    white_black_frame, // accumulate white + black (gray threshold, doubled)
    gray_threshold,    // threshold one gray plane against white/black or the phase mean
    gray_inverse,      // compare a gray plane with its inverse frame
    centerline_bit,    // threshold the centerline frame against the phase mean
};

struct Step {
    StepKind kind = StepKind::phase_block;
    int trigger = 0;           // run once frame `trigger` has arrived
    int stage = 0;             // order among steps with the same trigger
    int frame = -1;            // frame read (-1: none); phase_block: its first frame
    int frames = 1;            // frames read from `frame` on (phase_block: the block's steps)
    int frame2 = -1;           // inverse frame (gray_inverse)
    int index = -1;            // phase, gray or centerline index
    int k = 0;                 // gray plane (0 = MSB)
    bool first = false;        // first write of its accumulator or code: assign, not add
    bool sat_first = false;    // first step reading a frame: assigns the saturation byte
    std::uint8_t sat_bits = 0; // axis bits (1 = x, 2 = y) of the frames read
    // Streaming: a phase block's spans are decoded in `parts` slices, one at
    // each of the frames trigger .. trigger + parts - 1, so that no single
    // frame carries the whole block; its frames wait in slots until then.
    // Batch decoding ignores it.
    int parts = 1;
};

struct Plan {
    Size camera;
    Size projector;
    int frame_count = 0;
    std::vector<PhaseInfo> phases;
    std::vector<GrayInfo> grays;
    std::vector<CenterlineInfo> centerlines;
    int white_frame = -1;
    int black_frame = -1;
    AxisPlan axes[2];
    std::vector<Step> steps;     // execution order
    std::vector<int> frame_slot; // per frame: storage slot while it waits (-1 = none)
    int slot_count = 0;
    bool needs_full_storage = false; // a stage looks at neighbouring pixels
    bool uses_white_black = false;
};

// Throws std::invalid_argument with a message naming the block and the reason
// when the sequence cannot be decoded.
Plan make_plan(const Sequence& sequence, Size camera, Size projector);

} // namespace fpp::detail
