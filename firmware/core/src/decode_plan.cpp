#include "decode_plan.hpp"

#include "decode_weights.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace fpp::detail {

namespace {

[[noreturn]] void fail(const std::string& what) {
    throw std::invalid_argument("cannot decode sequence: " + what);
}

std::string block_name(const char* pattern, int index, int axis) {
    return std::string(pattern) + " block " + std::to_string(index) + " (axis " +
           (axis == 0 ? "x" : "y") + ")";
}

bool same_period(double a, double b) {
    return std::abs(a - b) <= 1e-9 * std::max(a, b);
}

void check_phase(const PhaseBlock& b, int index) {
    const std::string name = block_name("phase", index, b.axis == Axis::x ? 0 : 1);
    if (b.steps < 3)
        fail(name + ": steps must be >= 3, got " + std::to_string(b.steps));
    if (!(std::isfinite(b.period) && b.period > 0))
        fail(name + ": period must be > 0");
    if (b.shift_sign != 1 && b.shift_sign != -1)
        fail(name + ": shift_sign must be +1 or -1");
    if (!std::isfinite(b.phase_offset))
        fail(name + ": phase_offset must be finite");
}

void check_gray(const GrayBlock& b, int index) {
    const std::string name = block_name("gray", index, b.axis == Axis::x ? 0 : 1);
    if (b.bits < 1)
        fail(name + ": bits must be >= 1");
    if (b.bits + (b.complementary ? 1 : 0) > 16)
        fail(name + ": at most 16 bit planes are supported");
    if (!(std::isfinite(b.period) && b.period > 0))
        fail(name + ": period must be > 0");
}

void check_centerline(const CenterlineBlock& b, int index) {
    const std::string name = block_name("centerline", index, b.axis == Axis::x ? 0 : 1);
    if (!std::isfinite(b.position))
        fail(name + ": position must be finite");
    if (!(std::isfinite(b.width) && b.width > 0))
        fail(name + ": width must be > 0");
}

// Heterodyne levels over phase blocks sorted by period (ascending): the root is
// the least noisy level whose period covers the extent; below it every other
// level in descending period, so each step halves the ambiguity gently.
std::vector<HeterodyneLevel> heterodyne_levels(const std::vector<double>& periods, double extent,
                                               const std::string& axis_name) {
    const int n = static_cast<int>(periods.size());
    std::vector<std::vector<int>> coefs;
    if (n == 2) {
        coefs = {{1, 0, 0}, {0, 1, 0}, {1, -1, 0}};
    } else {
        coefs = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, -1, 0}, {0, 1, -1}, {1, 0, -1}, {1, -2, 1}};
    }
    std::vector<HeterodyneLevel> levels;
    for (const auto& c : coefs) {
        double inv = 0;
        for (int j = 0; j < n; ++j)
            inv += c[static_cast<std::size_t>(j)] / periods[static_cast<std::size_t>(j)];
        if (std::abs(inv) < 1e-12)
            continue;
        const int sign = inv < 0 ? -1 : 1;
        HeterodyneLevel level;
        level.period = 1.0 / std::abs(inv);
        int nonzero = 0;
        for (int j = 0; j < n; ++j) {
            level.coef[j] = sign * c[static_cast<std::size_t>(j)];
            if (level.coef[j] != 0)
                ++nonzero;
        }
        if (nonzero == 1) {
            for (int j = 0; j < n; ++j)
                if (level.coef[j] != 0)
                    level.single = j;
        }
        levels.push_back(level);
    }
    auto noise = [](const HeterodyneLevel& l) {
        double s = 0;
        for (int c : l.coef)
            s += double(c) * double(c);
        return l.period * std::sqrt(s);
    };
    int root = -1;
    for (int i = 0; i < static_cast<int>(levels.size()); ++i) {
        const auto& l = levels[static_cast<std::size_t>(i)];
        if (l.period + 1e-9 < extent)
            continue;
        if (root < 0 || noise(l) < noise(levels[static_cast<std::size_t>(root)]))
            root = i;
    }
    if (root < 0) {
        double widest = 0;
        for (const auto& l : levels)
            widest = std::max(widest, l.period);
        fail("phase blocks on axis " + axis_name + " form a heterodyne set whose widest beat (" +
             std::to_string(widest) + " px) does not cover the projector extent (" +
             std::to_string(extent) + " px)");
    }
    std::vector<HeterodyneLevel> chain{levels[static_cast<std::size_t>(root)]};
    std::vector<HeterodyneLevel> rest;
    for (int i = 0; i < static_cast<int>(levels.size()); ++i)
        if (i != root && levels[static_cast<std::size_t>(i)].period < chain[0].period)
            rest.push_back(levels[static_cast<std::size_t>(i)]);
    std::stable_sort(
        rest.begin(), rest.end(),
        [](const HeterodyneLevel& a, const HeterodyneLevel& b) { return a.period > b.period; });
    chain.insert(chain.end(), rest.begin(), rest.end());
    return chain;
}

void plan_axis(Plan& plan, int axis) {
    AxisPlan& ap = plan.axes[axis];
    const std::string axis_name = axis == 0 ? "x" : "y";
    ap.extent = axis == 0 ? plan.projector.width : plan.projector.height;
    std::vector<int> phases, grays, centerlines;
    for (int i = 0; i < static_cast<int>(plan.phases.size()); ++i)
        if (plan.phases[static_cast<std::size_t>(i)].axis == axis)
            phases.push_back(i);
    for (int i = 0; i < static_cast<int>(plan.grays.size()); ++i)
        if (plan.grays[static_cast<std::size_t>(i)].axis == axis)
            grays.push_back(i);
    for (int i = 0; i < static_cast<int>(plan.centerlines.size()); ++i)
        if (plan.centerlines[static_cast<std::size_t>(i)].axis == axis)
            centerlines.push_back(i);

    if (phases.empty()) {
        if (!grays.empty() || !centerlines.empty())
            fail("axis " + axis_name + " has a gray or centerline block but no phase block");
        return;
    }
    if (grays.size() > 1)
        fail("axis " + axis_name + " has more than one gray block");
    if (centerlines.size() > 1)
        fail("axis " + axis_name + " has more than one centerline block");
    ap.coded = true;
    auto period_of = [&](int p) { return plan.phases[static_cast<std::size_t>(p)].block.period; };

    if (grays.size() == 1) {
        GrayInfo& g = plan.grays[static_cast<std::size_t>(grays[0])];
        for (int p : phases)
            if (same_period(period_of(p), g.block.period)) {
                g.phase = p;
                break;
            }
        if (g.phase < 0)
            fail("gray block on axis " + axis_name + " indexes period " +
                 std::to_string(g.block.period) + " but no phase block on that axis has it");
        if (std::ldexp(g.block.period, g.block.bits) < ap.extent)
            fail("gray block on axis " + axis_name + " codes " + std::to_string(1 << g.block.bits) +
                 " periods of " + std::to_string(g.block.period) +
                 " px, fewer than the projector extent of " + std::to_string(ap.extent) + " px");
        ap.method = UnwrapMethod::gray;
        ap.phases = {g.phase};
        ap.gray = grays[0];
        ap.name = std::string(g.block.inverse ? "inverse-" : "") +
                  (g.block.complementary ? "complementary-gray" : "gray");
    } else if (phases.size() >= 2) {
        std::vector<int> sorted = phases;
        std::stable_sort(sorted.begin(), sorted.end(),
                         [&](int a, int b) { return period_of(a) < period_of(b); });
        for (std::size_t i = 1; i < sorted.size(); ++i)
            if (same_period(period_of(sorted[i]), period_of(sorted[i - 1])))
                fail("axis " + axis_name + " has two phase blocks with the same period " +
                     std::to_string(period_of(sorted[i])));
        if (period_of(sorted.back()) + 1e-9 >= ap.extent) {
            ap.method = UnwrapMethod::multi_period;
            ap.name = "multi-period";
            ap.phases.assign(sorted.rbegin(), sorted.rend()); // coarse to fine
        } else {
            if (sorted.size() > 3)
                fail("axis " + axis_name +
                     " has more than three phase blocks and none covers the projector extent");
            std::vector<double> periods;
            for (int p : sorted)
                periods.push_back(period_of(p));
            ap.levels = heterodyne_levels(periods, ap.extent, axis_name);
            ap.method = UnwrapMethod::heterodyne;
            ap.name = "heterodyne";
            ap.phases = sorted;
        }
    } else if (period_of(phases[0]) + 1e-9 >= ap.extent) {
        ap.method = UnwrapMethod::direct;
        ap.name = "direct";
        ap.phases = {phases[0]};
    } else if (centerlines.size() == 1) {
        ap.method = UnwrapMethod::centerline;
        ap.name = "centerline";
        ap.phases = {phases[0]};
        ap.centerline = centerlines[0];
        plan.centerlines[static_cast<std::size_t>(centerlines[0])].phase = phases[0];
    } else {
        fail("the phase block on axis " + axis_name + " (period " +
             std::to_string(period_of(phases[0])) +
             " px) is shorter than the projector extent and the sequence has no gray code, "
             "second period or centerline to unwrap it");
    }
    // Finest block: smallest period among those used.
    ap.report_phase = ap.phases[0];
    for (int p : ap.phases)
        if (period_of(p) < period_of(ap.report_phase))
            ap.report_phase = p;
    for (int p : ap.phases)
        plan.phases[static_cast<std::size_t>(p)].used = true;
}

} // namespace

Plan make_plan(const Sequence& sequence, Size camera, Size projector) {
    if (camera.width <= 0 || camera.height <= 0)
        fail("camera size must be positive");
    if (projector.width <= 0 || projector.height <= 0)
        fail("projector size must be positive");
    Plan plan;
    plan.camera = camera;
    plan.projector = projector;

    int frame = 0;
    for (std::size_t i = 0; i < sequence.size(); ++i) {
        const auto& block = sequence[i];
        const int index = static_cast<int>(i);
        if (const auto* p = std::get_if<PhaseBlock>(&block)) {
            check_phase(*p, index);
            PhaseInfo info;
            info.block = *p;
            info.first_frame = frame;
            info.axis = p->axis == Axis::x ? 0 : 1;
            for (int k = 0; k < p->steps; ++k) {
                const double delta = 2.0 * std::numbers::pi * k / p->steps;
                info.cos_w.push_back(static_cast<float>(std::cos(delta)));
                info.sin_w.push_back(static_cast<float>(-p->shift_sign * std::sin(delta)));
            }
            if (p->steps <= kMaxClassSteps) {
                const double step = 2.0 * std::numbers::pi / p->steps;
                for (int j = 0; j < cos_class_count(p->steps); ++j)
                    info.class_cos_w.push_back(static_cast<float>(std::cos(step * j)));
                for (int j = 0; j < sin_class_count(p->steps); ++j)
                    info.class_sin_w.push_back(
                        static_cast<float>(-p->shift_sign * std::sin(step * (j + 1))));
            }
            info.offset_fraction = static_cast<float>(p->phase_offset / (2.0 * std::numbers::pi));
            plan.phases.push_back(std::move(info));
        } else if (const auto* g = std::get_if<GrayBlock>(&block)) {
            check_gray(*g, index);
            GrayInfo info;
            info.block = *g;
            info.first_frame = frame;
            info.axis = g->axis == Axis::x ? 0 : 1;
            info.planes = g->bits + (g->complementary ? 1 : 0);
            plan.grays.push_back(info);
        } else if (const auto* c = std::get_if<CenterlineBlock>(&block)) {
            check_centerline(*c, index);
            CenterlineInfo info;
            info.block = *c;
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
    if (plan.phases.empty())
        fail("the sequence has no phase block, so no axis can be decoded");

    plan_axis(plan, 0);
    plan_axis(plan, 1);
    if (!plan.axes[0].coded && !plan.axes[1].coded)
        fail("no axis can be decoded");

    const bool have_white_black = plan.white_frame >= 0 && plan.black_frame >= 0;
    for (auto& g : plan.grays) {
        if (g.block.inverse)
            g.threshold = GrayThreshold::inverse;
        else if (have_white_black)
            g.threshold = GrayThreshold::white_black;
        else
            g.threshold = GrayThreshold::phase_mean;
        if (g.threshold == GrayThreshold::phase_mean)
            plan.phases[static_cast<std::size_t>(g.phase)].thresholds = true;
    }
    for (const auto& c : plan.centerlines)
        if (c.phase >= 0)
            plan.phases[static_cast<std::size_t>(c.phase)].thresholds = true;

    // Steps.
    std::vector<Step> steps;
    for (int b = 0; b < static_cast<int>(plan.phases.size()); ++b) {
        const PhaseInfo& p = plan.phases[static_cast<std::size_t>(b)];
        if (!p.used)
            continue;
        // The whole block once its last frame is there: the earlier frames
        // wait in slots, and batch and streaming run the same kernel.
        Step s;
        s.kind = StepKind::phase_block;
        s.trigger = p.last_frame();
        s.frame = p.first_frame;
        s.frames = p.block.steps;
        s.index = b;
        s.sat_bits = static_cast<std::uint8_t>(1u << p.axis);
        steps.push_back(s);
    }
    std::uint8_t white_black_bits = 0;
    for (const auto& g : plan.grays)
        if (g.threshold == GrayThreshold::white_black)
            white_black_bits = static_cast<std::uint8_t>(white_black_bits | (1u << g.axis));
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
            if (g.threshold == GrayThreshold::inverse) {
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
    std::stable_sort(steps.begin(), steps.end(), [](const Step& a, const Step& b) {
        return a.trigger != b.trigger ? a.trigger < b.trigger : a.stage < b.stage;
    });
    for (auto& s : steps)
        if (s.frame >= 0) {
            s.sat_first = true;
            break;
        }
    // A phase block is spread over the frames after its last one, up to the
    // first step that reads its result while frames still arrive (a gray or
    // centerline block thresholded against its mean); a block whose result
    // only the final unwrapping reads is spread up to the sequence's last
    // frame. kMaxPhaseParts slices bring the block's frame down to about a
    // quarter of its work; more would hold its frames longer for little gain.
    constexpr int kMaxPhaseParts = 4;
    for (auto& s : steps) {
        if (s.kind != StepKind::phase_block)
            continue;
        int deadline = plan.frame_count;
        for (const auto& reader : steps) {
            const bool reads_mean =
                (reader.kind == StepKind::gray_threshold &&
                 plan.grays[static_cast<std::size_t>(reader.index)].threshold ==
                     GrayThreshold::phase_mean &&
                 plan.grays[static_cast<std::size_t>(reader.index)].phase == s.index) ||
                (reader.kind == StepKind::centerline_bit &&
                 plan.centerlines[static_cast<std::size_t>(reader.index)].phase == s.index);
            if (reads_mean)
                deadline = std::min(deadline, reader.trigger);
        }
        s.parts = std::clamp(deadline - s.trigger, 1, kMaxPhaseParts);
    }
    plan.steps = std::move(steps);

    // Frames read after they arrive wait in a slot; slots are reused once free.
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

    for (const auto& ap : plan.axes) {
        if (!ap.coded)
            continue;
        if (ap.method == UnwrapMethod::centerline)
            plan.needs_full_storage = true;
        if (ap.method == UnwrapMethod::gray &&
            !plan.grays[static_cast<std::size_t>(ap.gray)].block.complementary)
            plan.needs_full_storage = true;
    }
    return plan;
}

} // namespace fpp::detail
