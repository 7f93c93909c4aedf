#include "decode_plan.hpp"

#include "decode_weights.hpp"
#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>

namespace fpp::detail {

namespace {

std::string block_name(const char* pattern, int index, int axis) {
    return std::string(pattern) + " block " + std::to_string(index) + " (axis " +
           (axis == 0 ? "x" : "y") + ")";
}

void check_phase(const Plan& plan, const PhaseBlock& b, int index) {
    const std::string name = block_name("phase", index, b.axis == Axis::x ? 0 : 1);
    auto refuse = [&](const char* key, const std::string& what) {
        refuse_sequence(plan, sequence_field(index, key), name + ": " + what);
    };
    if (b.shifting == PhaseShifting::two_plus_one && b.steps != 3)
        refuse("steps", "2+1 phase shifting has steps 3, got " + std::to_string(b.steps));
    if (b.steps < 3)
        refuse("steps", "steps must be >= 3, got " + std::to_string(b.steps));
    if (!(std::isfinite(b.period) && b.period > 0))
        refuse("period", "period must be > 0");
    if (b.shift_sign != 1 && b.shift_sign != -1)
        refuse("shift_sign", "shift_sign must be +1 or -1");
    if (!std::isfinite(b.phase_offset))
        refuse("phase_offset", "phase_offset must be finite");
    if (b.shifting == PhaseShifting::modulated) {
        if (!(std::isfinite(b.carrier_period) && b.carrier_period > 0))
            refuse("carrier_period", "carrier_period must be > 0");
        if (b.carrier_steps < 3 || b.carrier_steps > 16)
            refuse("carrier_steps",
                   "carrier_steps must be in [3, 16], got " + std::to_string(b.carrier_steps));
        if (b.steps > 16)
            refuse("steps",
                   "a modulated block has at most 16 steps, got " + std::to_string(b.steps));
    }
}

void check_micro(const Plan& plan, const MicroPhaseBlock& b, int index) {
    const std::string name = block_name("micro_phase", index, b.axis == Axis::x ? 0 : 1);
    auto refuse = [&](const std::string& field, const std::string& what) {
        refuse_sequence(plan, field, name + ": " + what);
    };
    const std::string periods = sequence_field(index, "periods");
    const std::string extra = sequence_field(index, "extra_phase_offsets");
    if (b.periods.size() < 2 || b.periods.size() > 16)
        refuse(periods, "needs 2 to 16 periods, got " + std::to_string(b.periods.size()));
    for (std::size_t k = 0; k < b.periods.size(); ++k)
        if (!(std::isfinite(b.periods[k]) && b.periods[k] > 0))
            refuse(yaml_fields::item(periods, k), "every period must be > 0");
    if (b.shift_sign != 1 && b.shift_sign != -1)
        refuse(sequence_field(index, "shift_sign"), "shift_sign must be +1 or -1");
    if (!std::isfinite(b.phase_offset))
        refuse(sequence_field(index, "phase_offset"), "phase_offset must be finite");
    if (!b.extra_phase_offsets.empty() && b.extra_phase_offsets.size() + 1 != b.periods.size())
        refuse(extra, "extra_phase_offsets needs one entry per period after the first (" +
                          std::to_string(b.periods.size() - 1) + "), got " +
                          std::to_string(b.extra_phase_offsets.size()));
    for (std::size_t k = 0; k < b.extra_phase_offsets.size(); ++k)
        if (!std::isfinite(b.extra_phase_offsets[k]))
            refuse(yaml_fields::item(extra, k), "every extra_phase_offsets entry must be finite");
}

void check_gray(const Plan& plan, const GrayBlock& b, int index) {
    const std::string name = block_name("gray", index, b.axis == Axis::x ? 0 : 1);
    auto refuse = [&](const char* key, const std::string& what) {
        refuse_sequence(plan, sequence_field(index, key), name + ": " + what);
    };
    if (b.bits < 1)
        refuse("bits", "bits must be >= 1");
    if (b.levels < 2)
        refuse("levels", "levels must be >= 2, got " + std::to_string(b.levels));
    const int planes = b.bits + (b.complementary ? 1 : 0);
    if (std::pow(double(b.levels), double(planes)) > 65536.0)
        refuse("levels", "levels^planes must be at most 65536 (16 bit planes), got " +
                             std::to_string(b.levels) + "^" + std::to_string(planes));
    if (!(std::isfinite(b.period) && b.period > 0))
        refuse("period", "period must be > 0");
    if (!std::isfinite(b.offset))
        refuse("offset", "offset must be finite");
}

void check_centerline(const Plan& plan, const CenterlineBlock& b, int index) {
    const std::string name = block_name("centerline", index, b.axis == Axis::x ? 0 : 1);
    if (!std::isfinite(b.position))
        refuse_sequence(plan, sequence_field(index, "position"),
                        name + ": position must be finite");
    if (!(std::isfinite(b.width) && b.width > 0))
        refuse_sequence(plan, sequence_field(index, "width"), name + ": width must be > 0");
}

// A micro phase block as a phase block of its first period (3 shifted

// The weights of `steps` frames shifted by shift_sign 2 pi k / steps, and the
// block's phase offset as a fraction of a turn.
void add_shift_weights(PhaseInfo& info, int steps, int shift_sign, double phase_offset) {
    for (int k = 0; k < steps; ++k) {
        const double delta = 2.0 * std::numbers::pi * k / steps;
        info.cos_w.push_back(static_cast<float>(std::cos(delta)));
        info.sin_w.push_back(static_cast<float>(-shift_sign * std::sin(delta)));
    }
    info.offset_fraction = static_cast<float>(phase_offset / (2.0 * std::numbers::pi));
}

// frames) followed by one frame of each other period.
PhaseInfo micro_info(const MicroPhaseBlock& m, int first_frame, int frames) {
    PhaseInfo info;
    info.kind = PhaseKind::micro;
    info.block.axis = m.axis;
    info.block.period = m.periods[0];
    info.block.steps = 3;
    info.block.shift_sign = m.shift_sign;
    info.block.phase_offset = m.phase_offset;
    info.first_frame = first_frame;
    info.frames = frames;
    info.axis = m.axis == Axis::x ? 0 : 1;
    info.micro_periods = m.periods;
    info.micro_extra_offsets.assign(m.periods.size() - 1, 0.0f);
    for (std::size_t f = 0; f < m.extra_phase_offsets.size() && f + 1 < m.periods.size(); ++f)
        info.micro_extra_offsets[f] = static_cast<float>(m.extra_phase_offsets[f]);
    add_shift_weights(info, 3, m.shift_sign, m.phase_offset);
    return info;
}

// A phase block of standard, 2+1 or modulated shifting: its weights.
PhaseInfo phase_info(const PhaseBlock& p, int first_frame, int frames) {
    PhaseInfo info;
    info.block = p;
    info.first_frame = first_frame;
    info.frames = frames;
    info.axis = p.axis == Axis::x ? 0 : 1;
    if (p.shifting == PhaseShifting::two_plus_one)
        info.kind = PhaseKind::two_plus_one;
    if (p.shifting == PhaseShifting::modulated) {
        info.kind = PhaseKind::modulated;
        for (int j = 0; j < p.carrier_steps; ++j) {
            const double delta = 2.0 * std::numbers::pi * j / p.carrier_steps;
            info.carrier_cos.push_back(static_cast<float>(std::cos(delta)));
            info.carrier_sin.push_back(static_cast<float>(std::sin(delta)));
        }
    }
    add_shift_weights(info, p.steps, p.shift_sign, p.phase_offset);
    if (p.steps <= kMaxClassSteps) {
        const double step = 2.0 * std::numbers::pi / p.steps;
        for (int j = 0; j < cos_class_count(p.steps); ++j)
            info.class_cos_w.push_back(static_cast<float>(std::cos(step * j)));
        for (int j = 0; j < sin_class_count(p.steps); ++j)
            info.class_sin_w.push_back(
                static_cast<float>(-p.shift_sign * std::sin(step * (j + 1))));
    }
    return info;
}

// A gray block: its planes and the weight of each plane's digit.
GrayInfo gray_info(const GrayBlock& g, int first_frame, Size projector) {
    GrayInfo info;
    info.block = g;
    info.first_frame = first_frame;
    info.axis = g.axis == Axis::x ? 0 : 1;
    info.planes = g.bits + (g.complementary ? 1 : 0);
    for (int k = 0; k < info.planes; ++k) {
        const int position = g.order == DigitOrder::msb_first ? info.planes - 1 - k : k;
        info.weight.push_back(
            static_cast<std::uint16_t>(std::lround(std::pow(double(g.levels), double(position)))));
    }
    // fpp-capture/1's plain Gray keeps its vectorised gray_to_binary.
    if (g.code != CodeKind::gray || g.levels != 2 || g.offset != 0.0 || g.wrap)
        build_step_table(info, g.axis == Axis::x ? projector.width : projector.height);
    return info;
}

// The sequence's blocks, checked, in the plan's lists with their frames.
void collect_blocks(Plan& plan, const Sequence& sequence) {
    int frame = 0;
    for (std::size_t i = 0; i < sequence.size(); ++i) {
        const auto& block = sequence[i];
        const int index = static_cast<int>(i);
        if (const auto* p = std::get_if<PhaseBlock>(&block)) {
            check_phase(plan, *p, index);
            plan.phases.push_back(phase_info(*p, frame, frame_count(block)));
            plan.phases.back().sequence_index = index;
        } else if (const auto* m = std::get_if<MicroPhaseBlock>(&block)) {
            check_micro(plan, *m, index);
            plan.phases.push_back(micro_info(*m, frame, frame_count(block)));
            plan.phases.back().sequence_index = index;
        } else if (const auto* g = std::get_if<GrayBlock>(&block)) {
            check_gray(plan, *g, index);
            plan.grays.push_back(gray_info(*g, frame, plan.projector));
            plan.grays.back().sequence_index = index;
        } else if (const auto* c = std::get_if<CenterlineBlock>(&block)) {
            check_centerline(plan, *c, index);
            CenterlineInfo info;
            info.block = *c;
            info.sequence_index = index;
            info.frame = frame;
            info.axis = c->axis == Axis::x ? 0 : 1;
            plan.centerlines.push_back(info);
        } else if (std::holds_alternative<WhiteBlock>(block)) {
            if (plan.white_frame < 0)
                plan.white_frame = frame;
        } else if (std::holds_alternative<BlackBlock>(block)) {
            if (plan.black_frame < 0)
                plan.black_frame = frame;
        }
        frame += frame_count(block);
    }
    plan.frame_count = frame;
    if (plan.phases.empty() && plan.grays.empty())
        refuse_sequence(plan, "sequence",
                        "the sequence has no phase block (nor micro_phase or gray block), so no "
                        "axis can be decoded");
}

// How each gray block's planes are thresholded (white and black, inverse
// frames or the mean of the phase block it indexes), refusing the blocks
// that cannot be; marks the phase blocks whose mean a threshold reads.
void choose_gray_thresholds(Plan& plan) {
    const bool have_white_black = plan.white_frame >= 0 && plan.black_frame >= 0;
    for (std::size_t gi = 0; gi < plan.grays.size(); ++gi) {
        GrayInfo& g = plan.grays[gi];
        const std::string name = block_name("gray", static_cast<int>(gi), g.axis) + " (" +
                                 std::to_string(g.block.levels) + " levels)";
        auto refuse = [&](const std::string& field, const std::string& what) {
            refuse_sequence(plan, field, name + ": " + what);
        };
        if (g.block.wrap && (g.phase < 0 || g.block.complementary || g.block.levels != 2))
            refuse(sequence_field(g.sequence_index, "wrap"),
                   "wrap needs a two-level code without the complementary plane that indexes a "
                   "phase block (the phase tells its last step from its first)");
        if (g.block.levels > 2) {
            if (g.block.inverse)
                refuse(sequence_field(g.sequence_index, "inverse"),
                       "inverse frames are not defined for more than 2 levels");
            if (have_white_black) {
                g.threshold = GrayThreshold::white_black;
                plan.uses_levels = true;
            } else if (g.phase >= 0) {
                g.threshold = GrayThreshold::phase_levels; // SLMaster's interzone code
            } else {
                refuse(sequence_field(g.sequence_index, "levels"),
                       "multi-level digits need white and black frames in the sequence, or a "
                       "phase block of their period on their axis to scale them");
            }
        } else if (g.block.inverse) {
            g.threshold = GrayThreshold::inverse;
        } else if (have_white_black) {
            g.threshold = GrayThreshold::white_black;
        } else if (g.phase >= 0) {
            g.threshold = GrayThreshold::phase_mean;
        } else {
            refuse(sequence_field(g.sequence_index),
                   "a code-only axis needs inverse frames or white and black frames to "
                   "threshold its planes");
        }
        if (g.phase < 0 && g.threshold == GrayThreshold::white_black)
            plan.uses_levels = true; // its modulation is (white - black) / 2
        if (doubt_against_levels(g))
            for (std::uint16_t w : g.weight)
                if (static_cast<double>(w) * g.block.period < 2.0)
                    g.fine_planes = static_cast<std::uint16_t>(g.fine_planes | w);
        if (g.threshold == GrayThreshold::phase_mean)
            plan.phases[static_cast<std::size_t>(g.phase)].thresholds = true;
    }
    for (const auto& c : plan.centerlines)
        if (c.phase >= 0)
            plan.phases[static_cast<std::size_t>(c.phase)].thresholds = true;
}

// One step per used phase block: the whole block once its last frame is
// there (the earlier frames wait in slots, and batch and streaming run the
// same kernel).
void add_phase_block_steps(const Plan& plan, std::vector<Step>& steps) {
    for (int b = 0; b < static_cast<int>(plan.phases.size()); ++b) {
        const PhaseInfo& p = plan.phases[static_cast<std::size_t>(b)];
        if (!p.used)
            continue;
        Step s;
        s.kind = StepKind::phase_block;
        s.trigger = p.last_frame();
        s.frame = p.first_frame;
        s.frames = p.frames;
        s.index = b;
        s.sat_bits = static_cast<std::uint8_t>(1u << p.axis);
        steps.push_back(s);
    }
}

// The white and black frames: kept as levels (n-ary digits, code-only
// contrast) and summed into the white + black threshold.
void add_white_black_steps(Plan& plan, std::vector<Step>& steps) {
    std::uint8_t white_black_bits = 0;
    for (const auto& g : plan.grays)
        if (g.threshold == GrayThreshold::white_black)
            white_black_bits = static_cast<std::uint8_t>(white_black_bits | (1u << g.axis));
    if (plan.uses_levels) {
        for (int fr : {plan.black_frame, plan.white_frame}) {
            Step s;
            s.kind = StepKind::level_frame;
            s.trigger = s.frame = fr;
            s.index = fr == plan.white_frame ? 1 : 0;
            s.sat_bits = white_black_bits;
            steps.push_back(s);
        }
    }
    if (white_black_bits != 0) {
        plan.uses_white_black = true;
        for (int fr : {plan.white_frame, plan.black_frame}) {
            Step s;
            s.kind = StepKind::white_black_frame;
            s.trigger = s.frame = fr;
            s.first = fr == std::min(plan.white_frame, plan.black_frame);
            s.sat_bits = white_black_bits;
            steps.push_back(s);
        }
    }
}

// Each gray plane once it and its threshold are there; then the code-only
// axes' modulation and mean from white and black.
void add_gray_steps(const Plan& plan, std::vector<Step>& steps) {
    const int white_black_ready = std::max(plan.white_frame, plan.black_frame);
    for (int gi = 0; gi < static_cast<int>(plan.grays.size()); ++gi) {
        const GrayInfo& g = plan.grays[static_cast<std::size_t>(gi)];
        const auto bit = static_cast<std::uint8_t>(1u << g.axis);
        for (int j = 0; j < g.planes; ++j) {
            Step s;
            s.index = gi;
            s.k = j;
            s.first = j == 0;
            s.sat_bits = bit;
            s.stage = 2;
            if (g.block.levels > 2) {
                s.kind = StepKind::gray_digit;
                s.frame = g.first_frame + j;
                const int ready = g.threshold == GrayThreshold::phase_levels
                                      ? plan.phases[static_cast<std::size_t>(g.phase)].last_frame()
                                      : white_black_ready;
                s.trigger = std::max(s.frame, ready);
            } else if (g.threshold == GrayThreshold::inverse) {
                s.kind = StepKind::gray_inverse;
                s.frame = g.first_frame + 2 * j;
                s.frame2 = s.frame + 1;
                s.trigger = s.frame2;
            } else {
                s.kind = StepKind::gray_threshold;
                s.frame = g.first_frame + j;
                const int ready = g.threshold == GrayThreshold::white_black
                                      ? white_black_ready
                                      : plan.phases[static_cast<std::size_t>(g.phase)].last_frame();
                s.trigger = std::max(s.frame, ready);
            }
            steps.push_back(s);
        }
    }
    for (int gi = 0; gi < static_cast<int>(plan.grays.size()); ++gi) {
        const GrayInfo& g = plan.grays[static_cast<std::size_t>(gi)];
        if (g.phase >= 0 || g.threshold != GrayThreshold::white_black)
            continue;
        Step s; // the code-only axis's modulation and mean, from white and black
        s.kind = StepKind::code_levels;
        s.index = gi;
        s.stage = 1;
        s.trigger = white_black_ready;
        steps.push_back(s);
    }
}

// Each used centerline frame once it and its phase block's mean are there.
void add_centerline_steps(const Plan& plan, std::vector<Step>& steps) {
    for (int ci = 0; ci < static_cast<int>(plan.centerlines.size()); ++ci) {
        const CenterlineInfo& c = plan.centerlines[static_cast<std::size_t>(ci)];
        if (c.phase < 0)
            continue; // not used (the axis is decoded otherwise)
        Step s;
        s.kind = StepKind::centerline_bit;
        s.frame = c.frame;
        s.index = ci;
        s.stage = 2;
        s.sat_bits = static_cast<std::uint8_t>(1u << c.axis);
        s.trigger = std::max(c.frame, plan.phases[static_cast<std::size_t>(c.phase)].last_frame());
        steps.push_back(s);
    }
}

// Execution order: by trigger frame, then stage; the first step that reads a
// frame assigns the saturation byte.
void order_steps(std::vector<Step>& steps) {
    std::stable_sort(steps.begin(), steps.end(), [](const Step& a, const Step& b) {
        return a.trigger != b.trigger ? a.trigger < b.trigger : a.stage < b.stage;
    });
    for (auto& s : steps)
        if (s.frame >= 0) {
            s.sat_first = true;
            break;
        }
}

// A phase block is spread over the frames after its last one, up to the
// first step that reads its result while frames still arrive (a gray or
// centerline block thresholded against its mean, n-ary digits scaled by its
// mean and modulation); a block whose result
// only the final unwrapping reads is spread up to the sequence's last
// frame. kMaxPhaseParts slices bring the block's frame down to about a
// quarter of its work; more would hold its frames longer for little gain.
void spread_phase_blocks(const Plan& plan, std::vector<Step>& steps) {
    constexpr int kMaxPhaseParts = 4;
    for (auto& s : steps) {
        if (s.kind != StepKind::phase_block)
            continue;
        int deadline = plan.frame_count;
        for (const auto& reader : steps) {
            const GrayInfo* gray =
                reader.kind == StepKind::gray_threshold || reader.kind == StepKind::gray_digit
                    ? &plan.grays[static_cast<std::size_t>(reader.index)]
                    : nullptr;
            const bool reads_mean =
                (gray != nullptr && gray->phase == s.index &&
                 (gray->threshold == GrayThreshold::phase_mean ||
                  gray->threshold == GrayThreshold::phase_levels)) ||
                (reader.kind == StepKind::centerline_bit &&
                 plan.centerlines[static_cast<std::size_t>(reader.index)].phase == s.index);
            if (reads_mean)
                deadline = std::min(deadline, reader.trigger);
        }
        s.parts = std::clamp(deadline - s.trigger, 1, kMaxPhaseParts);
    }
}

// Plan::steps: every step, in execution order.
void make_steps(Plan& plan) {
    std::vector<Step> steps;
    add_phase_block_steps(plan, steps);
    add_white_black_steps(plan, steps);
    add_gray_steps(plan, steps);
    add_centerline_steps(plan, steps);
    order_steps(steps);
    spread_phase_blocks(plan, steps);
    plan.steps = std::move(steps);
}

// Frames read after they arrive wait in a slot; slots are reused once free.
void assign_frame_slots(Plan& plan) {
    plan.frame_slot.assign(static_cast<std::size_t>(plan.frame_count), -1);
    std::vector<int> keep_until(static_cast<std::size_t>(plan.frame_count), -1);
    auto keep = [&](int fr, int until) {
        if (fr >= 0 && until > fr)
            keep_until[static_cast<std::size_t>(fr)] =
                std::max(keep_until[static_cast<std::size_t>(fr)], until);
    };
    for (const auto& s : plan.steps) {
        const int last_read = s.trigger + s.parts - 1;
        for (int f = 0; f < s.frames; ++f)
            keep(s.frame < 0 ? -1 : s.frame + f, last_read);
        keep(s.frame2, last_read);
    }
    std::vector<int> slot_free_after; // per slot: last frame index that reads it
    for (int fr = 0; fr < plan.frame_count; ++fr) {
        const int until = keep_until[static_cast<std::size_t>(fr)];
        if (until < 0)
            continue;
        int slot = -1;
        for (int s = 0; s < static_cast<int>(slot_free_after.size()); ++s)
            if (slot_free_after[static_cast<std::size_t>(s)] < fr) {
                slot = s;
                break;
            }
        if (slot < 0) {
            slot = static_cast<int>(slot_free_after.size());
            slot_free_after.push_back(-1);
        }
        slot_free_after[static_cast<std::size_t>(slot)] = until;
        plan.frame_slot[static_cast<std::size_t>(fr)] = slot;
    }
    plan.slot_count = static_cast<int>(slot_free_after.size());
}

// Stages that look at neighbouring pixels (centerline regions, the repair
// of plain Gray code edges) need whole images.
void mark_full_storage(Plan& plan) {
    for (const auto& ap : plan.axes) {
        if (!ap.coded)
            continue;
        if (ap.method == UnwrapMethod::centerline)
            plan.needs_full_storage = true;
        if (ap.method == UnwrapMethod::gray &&
            !plan.grays[static_cast<std::size_t>(ap.gray)].block.complementary)
            plan.needs_full_storage = true;
    }
}

} // namespace

std::string sequence_field(int index, std::string_view key) {
    const std::string block = yaml_fields::item("sequence", static_cast<std::size_t>(index));
    return key.empty() ? block : yaml_fields::child(block, key);
}

void refuse_sequence(const Plan& plan, const std::string& field, const std::string& what) {
    throw InputError(plan.origin, field, "cannot decode sequence: " + what);
}

Plan make_plan(const Sequence& sequence, Size camera, Size projector,
               const std::filesystem::path& origin) {
    Plan plan;
    plan.origin = origin;
    if (camera.width <= 0 || camera.height <= 0)
        refuse_sequence(plan, "camera", "camera size must be positive");
    if (projector.width <= 0 || projector.height <= 0)
        refuse_sequence(plan, "projector", "projector size must be positive");
    plan.camera = camera;
    plan.projector = projector;

    collect_blocks(plan, sequence);
    plan_axis(plan, 0);
    plan_axis(plan, 1);
    if (!plan.axes[0].coded && !plan.axes[1].coded)
        refuse_sequence(plan, "sequence", "no axis can be decoded");
    choose_gray_thresholds(plan);
    make_steps(plan);
    assign_frame_slots(plan);
    mark_full_storage(plan);
    return plan;
}

} // namespace fpp::detail
