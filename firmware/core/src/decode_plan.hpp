#pragma once
// Decoding plan: which blocks a sequence decodes each axis with, and the list
// of steps, each run once the frames it reads have arrived. Both the batch and
// the streaming decoder execute the same steps in the same order, which is
// what makes them bit-identical.

#include "fpp/decoder.hpp"
#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace fpp::detail {

enum class UnwrapMethod { direct, multi_period, heterodyne, gray, centerline, code, micro };

// How a phase block's frames give the sums c, s, a of its phase.
enum class PhaseKind { standard, two_plus_one, modulated, micro };

struct PhaseInfo {
    PhaseBlock block; // micro: period = periods[0], steps = 3
    PhaseKind kind = PhaseKind::standard;
    int sequence_index = 0; // the block's index in the sequence (error messages)
    int first_frame = 0;
    int frames = 0; // frames the block occupies
    int axis = 0;   // 0 = x, 1 = y
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
    // modulated: cos and sin of the carrier shifts 2 pi j / carrier_steps.
    std::vector<float> carrier_cos;
    std::vector<float> carrier_sin;
    // micro: the periods (projector px), the candidate fringe orders k of the
    // first period covering the projector, and cos / sin of 2 pi k P_1 / P_f
    // per other period f (row f - 1, candidate k - first_order).
    std::vector<double> micro_periods;
    std::vector<float> micro_extra_offsets; // per other period, rad (0 when the block has none)
    int first_order = 0;
    int orders = 0;
    std::vector<float> order_cos;
    std::vector<float> order_sin;
    int last_frame() const { return first_frame + frames - 1; }
};

// How a code plane is read: against (white + black) / 2 (n-ary: scaled by
// white and black), its inverse frame, the mean A of the phase block it
// indexes, or (n-ary without white and black) scaled by that block's A - B
// and A + B.
enum class GrayThreshold { white_black, inverse, phase_mean, phase_levels };

struct GrayInfo {
    GrayBlock block;
    int sequence_index = 0; // the block's index in the sequence (error messages)
    int first_frame = 0;
    int axis = 0;
    int planes = 0; // bits (+1 if complementary)
    GrayThreshold threshold = GrayThreshold::phase_mean;
    int phase = -1; // index into Plan::phases: the block it indexes (and thresholds against);
                    // -1: the block codes its axis alone (UnwrapMethod::code)
    // Weight of each plane's digit in the stored code value (capture order):
    // levels^position, position 0 = least significant digit.
    std::vector<std::uint16_t> weight;
    // Code value -> code step n (after the wrap of offset codes, see
    // decoder.hpp), or kInvalidStep for values no step inside the projector
    // uses. Empty for the plain Gray of fpp-capture/1 (n = gray_to_binary).
    std::vector<float> step_of_code;
    float max_step = 0; // largest valid n
    // Code-only axes (phase < 0), 2 x (levels^planes) entries: [v] the centre
    // of the projector pixels showing the step of code value v,
    // (ceil(offset + n u) + ceil(offset + (n + 1) u)) / 2 - 1/2; [count + v]
    // the pixel-grid edge between the steps of values v - 1 and v,
    // ceil(offset + n u) - 1/2 (natural binary's doubtful digits, see
    // unwrap_code_row). NaN where the value shows no step (or, for an edge,
    // the two values are not neighbouring steps and neither alone is valid).
    std::vector<float> code_coordinate;
    // doubt_against_levels blocks: the code weights of the planes whose
    // stripes (one code step each) are narrower than two projector pixels,
    // runs of single pixels on its grid that the projector's blur fills in.
    std::uint16_t fine_planes = 0;
};

// Longest run of doubtful digits 0..j that unwrap_code_row resolves to the
// edge inside their cell (2^(j+1) - 1, j = 3: a 16-step cell). Longer runs
// made by noise put the pixel on an edge 2^(j+1) steps away as often as not
// (test_decode_families.cpp, NaturalBinaryCodeOnly).
inline constexpr std::uint32_t kMaxCarryRun = 15;

inline constexpr float kInvalidStep = 1e9f;

// The flag a code plane sets in the doubt plane (decode_family_kernels.hpp):
// its code weight for two-level codes (distinct bits, which lets natural
// binary's carry edges be recognised), else a bit of its own.
inline std::uint16_t doubt_flag(const GrayInfo& g, int plane) {
    return g.block.levels == 2 ? g.weight[static_cast<std::size_t>(plane)]
                               : static_cast<std::uint16_t>(1u << plane);
}

// Natural binary on a code-only axis thresholded by white and black: its
// digits are also doubtful near the threshold relative to W - B
// (doubt_levels_row), and unwrap_code_row resolves them.
inline bool doubt_against_levels(const GrayInfo& g) {
    return g.phase < 0 && g.threshold == GrayThreshold::white_black && g.block.levels == 2 &&
           g.block.code == CodeKind::binary && !g.block.complementary;
}
// Whether plane flag `flag` of such a block is judged against W - B.
inline bool doubt_against_levels(const GrayInfo& g, std::uint16_t flag) {
    return doubt_against_levels(g) && (g.fine_planes & flag) != 0;
}

struct CenterlineInfo {
    CenterlineBlock block;
    int sequence_index = 0; // the block's index in the sequence (error messages)
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
    level_frame,       // copy the white (index 1) or black (index 0) frame
    gray_digit,        // n-ary plane: digit = round((I - black) / (white - black) (L - 1)),
                       // black and white the frames or the phase block's A - B and A + B
    code_levels,       // code-only block with white/black: modulation and mean
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
    bool uses_levels = false;     // white and black kept (n-ary digits, code-only contrast)
    std::filesystem::path origin; // the file InputErrors name (see make_plan)
};

// The field name of sequence block `index` (and its `key`), as the
// capture-set reader names it.
std::string sequence_field(int index, std::string_view key = {});

// Throws InputError(plan.origin, field, "cannot decode sequence: " + what).
[[noreturn]] void refuse_sequence(const Plan& plan, const std::string& field,
                                  const std::string& what);

// Code value -> step table of a Gray block over `extent` projector pixels.
void build_step_table(GrayInfo& g, double extent);

// Plans one axis (decode_plan_axis.cpp).
void plan_axis(Plan& plan, int axis);

// Throws fpp::InputError(origin, field, "cannot decode sequence: ...") when
// the sequence cannot be decoded: the field names the block as the
// capture-set reader does ("sequence[2].period", "sequence[2]"; "sequence"
// for the sequence as a whole; "camera", "projector" for the sizes), the
// message the block and the reason. `origin` is the manifest the sequence
// came from (decode(): the capture's capture.yaml), else kDecoderOrigin
// (decoder.hpp).
Plan make_plan(const Sequence& sequence, Size camera, Size projector,
               const std::filesystem::path& origin = kDecoderOrigin);

} // namespace fpp::detail
