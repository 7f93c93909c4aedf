// Per-axis planning (decode_plan.hpp): which blocks decode an axis and by
// which unwrapping method, with the tables that method needs (gray code steps,
// micro-phase orders, heterodyne levels).

#include "decode_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace fpp::detail {

namespace {

bool same_period(double a, double b) {
    return std::abs(a - b) <= 1e-9 * std::max(a, b);
}

std::string axis_letter(int axis) {
    return axis == 0 ? "x" : "y";
}

// Digit `digit` (0 = least significant) of code step n's codeword, as
// patterns.cpp renders it: natural base-L digits, or the reflected L-ary Gray
// code (a digit mirrored when the Gray digits above it sum to an odd number).
int codeword_digit(const GrayBlock& b, int digits, std::int64_t n, int digit) {
    std::int64_t place = 1;
    for (int i = 1; i < digits; ++i)
        place *= b.levels;
    int gray_sum = 0;
    for (int i = digits - 1; i >= 0; --i, place /= b.levels) {
        const auto natural = static_cast<int>((n / place) % b.levels);
        const int value =
            (b.code == CodeKind::gray && gray_sum % 2 == 1) ? b.levels - 1 - natural : natural;
        if (i == digit)
            return value;
        gray_sum += value;
    }
    return 0;
}

// GrayInfo::code_coordinate from step_of_code. A table lookup per pixel
// instead of two ceilings: the code-only decode is otherwise bound by them.
void build_coordinate_table(GrayInfo& g) {
    const double unit = g.block.complementary ? g.block.period / 2.0 : g.block.period;
    const double offset = g.block.offset;
    const std::size_t count = g.step_of_code.size();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    auto valid = [&](std::size_t v) { return g.step_of_code[v] <= g.max_step; };
    auto step = [&](std::size_t v) { return static_cast<double>(g.step_of_code[v]); };
    auto centre = [&](std::size_t v) {
        return static_cast<float>(0.5 * (std::ceil(offset + step(v) * unit) +
                                         std::ceil(offset + (step(v) + 1.0) * unit)) -
                                  0.5);
    };
    g.code_coordinate.assign(2 * count, nan);
    for (std::size_t v = 0; v < count; ++v) {
        if (valid(v))
            g.code_coordinate[v] = centre(v);
        if (v == 0)
            continue;
        float& edge = g.code_coordinate[count + v];
        if (valid(v) && valid(v - 1) && step(v) == step(v - 1) + 1.0)
            edge = static_cast<float>(std::ceil(offset + step(v) * unit) - 0.5);
        else if (valid(v) != valid(v - 1)) // at an end of the projector: the step inside it
            edge = centre(valid(v) ? v : v - 1);
    }
}

// The candidate fringe orders of a micro block's first period: every k whose
// period [k P_1, (k + 1) P_1) meets the projector with its pixel of margin.
void plan_micro_orders(PhaseInfo& info, double extent) {
    const double p1 = info.micro_periods[0];
    info.first_order = static_cast<int>(std::floor(-1.5 / p1));
    const int last = static_cast<int>(std::floor((extent + 0.5) / p1));
    info.orders = last - info.first_order + 1;
    const std::size_t others = info.micro_periods.size() - 1;
    info.order_cos.assign(others * static_cast<std::size_t>(info.orders), 0.0f);
    info.order_sin.assign(others * static_cast<std::size_t>(info.orders), 0.0f);
    for (std::size_t f = 0; f < others; ++f)
        for (int i = 0; i < info.orders; ++i) {
            const double k = info.first_order + i;
            const double turns = k * p1 / info.micro_periods[f + 1];
            const double angle = 2.0 * std::numbers::pi * (turns - std::floor(turns));
            const std::size_t at = f * static_cast<std::size_t>(info.orders) + std::size_t(i);
            info.order_cos[at] = static_cast<float>(std::cos(angle));
            info.order_sin[at] = static_cast<float>(std::sin(angle));
        }
}

// Every level a heterodyne set of two or three periods (ascending) can form:
// the blocks themselves and their beats, each with positive period.
std::vector<HeterodyneLevel> candidate_levels(const std::vector<double>& periods) {
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
    return levels;
}

// Heterodyne levels over phase blocks sorted by period (ascending): the root is
// the least noisy level whose period covers the extent; below it every other
// level in descending period, so each step halves the ambiguity gently.
std::vector<HeterodyneLevel> heterodyne_levels(const Plan& plan, const std::vector<double>& periods,
                                               double extent, const std::string& axis_name) {
    const std::vector<HeterodyneLevel> levels = candidate_levels(periods);
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
        refuse_sequence(plan, "sequence",
                        "phase blocks on axis " + axis_name +
                            " form a heterodyne set whose widest beat (" + std::to_string(widest) +
                            " px) does not cover the projector extent (" + std::to_string(extent) +
                            " px)");
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

// The blocks of one axis: indices into Plan::phases, grays, centerlines.
struct AxisBlocks {
    std::vector<int> phases, grays, centerlines;
};

AxisBlocks blocks_on_axis(const Plan& plan, int axis) {
    AxisBlocks blocks;
    for (int i = 0; i < static_cast<int>(plan.phases.size()); ++i)
        if (plan.phases[static_cast<std::size_t>(i)].axis == axis)
            blocks.phases.push_back(i);
    for (int i = 0; i < static_cast<int>(plan.grays.size()); ++i)
        if (plan.grays[static_cast<std::size_t>(i)].axis == axis)
            blocks.grays.push_back(i);
    for (int i = 0; i < static_cast<int>(plan.centerlines.size()); ++i)
        if (plan.centerlines[static_cast<std::size_t>(i)].axis == axis)
            blocks.centerlines.push_back(i);
    return blocks;
}

double period_of(const Plan& plan, int p) {
    return plan.phases[static_cast<std::size_t>(p)].block.period;
}

// Appends, not operator+ on literals: GCC 12 warns falsely (-Wrestrict) there.
std::string code_name(const GrayBlock& b) {
    std::string name;
    if (b.offset != 0.0)
        name += "shifted-";
    if (b.inverse)
        name += "inverse-";
    if (b.complementary)
        name += "complementary-";
    name += name_of(kCodeKindNames, b.code, "gray");
    return name;
}

std::string level_suffix(const GrayBlock& b) {
    std::string suffix;
    if (b.levels > 2) {
        suffix += '-';
        suffix += std::to_string(b.levels);
        suffix += "-level";
    }
    return suffix;
}

// A gray block must number every code step across the axis's extent.
void check_cover(const Plan& plan, const GrayInfo& g, int axis) {
    const GrayBlock& b = g.block;
    const double extent = plan.axes[axis].extent;
    const double cover = b.period * std::pow(double(b.levels), double(b.bits));
    if (cover + 1e-9 < extent)
        refuse_sequence(plan, sequence_field(g.sequence_index, "bits"),
                        "gray block on axis " + axis_letter(axis) + " codes " +
                            std::to_string(cover) + " px, fewer than the projector extent of " +
                            std::to_string(extent) + " px");
}

// At most one gray and one centerline block on an axis.
void check_one_code(const Plan& plan, int axis, const AxisBlocks& blocks) {
    if (blocks.grays.size() > 1)
        refuse_sequence(
            plan,
            sequence_field(plan.grays[static_cast<std::size_t>(blocks.grays[1])].sequence_index),
            "axis " + axis_letter(axis) + " has more than one gray block");
    if (blocks.centerlines.size() > 1)
        refuse_sequence(
            plan,
            sequence_field(
                plan.centerlines[static_cast<std::size_t>(blocks.centerlines[1])].sequence_index),
            "axis " + axis_letter(axis) + " has more than one centerline block");
}

// A micro_phase block codes its axis alone. False when the axis has none.
bool plan_micro_axis(Plan& plan, int axis, const AxisBlocks& blocks) {
    AxisPlan& ap = plan.axes[axis];
    for (int p : blocks.phases) {
        const PhaseInfo& info = plan.phases[static_cast<std::size_t>(p)];
        if (info.kind != PhaseKind::micro)
            continue;
        if (blocks.phases.size() > 1 || !blocks.grays.empty() || !blocks.centerlines.empty())
            refuse_sequence(plan, sequence_field(info.sequence_index),
                            "axis " + axis_letter(axis) +
                                " has a micro_phase block and other coding blocks: micro phase "
                                "shifting codes its axis alone");
        ap.coded = true;
        ap.method = UnwrapMethod::micro;
        ap.name = "micro-phase";
        ap.phases = {p};
        ap.report_phase = p;
        plan.phases[static_cast<std::size_t>(p)].used = true;
        plan_micro_orders(plan.phases[static_cast<std::size_t>(p)], ap.extent);
        return true;
    }
    return false;
}

// An axis without phase blocks: its gray block alone gives the coordinate
// (or, without one, the axis is not coded).
void plan_code_only_axis(Plan& plan, int axis, const AxisBlocks& blocks) {
    AxisPlan& ap = plan.axes[axis];
    if (!blocks.centerlines.empty())
        refuse_sequence(
            plan,
            sequence_field(
                plan.centerlines[static_cast<std::size_t>(blocks.centerlines[0])].sequence_index),
            "axis " + axis_letter(axis) + " has a centerline block but no phase block");
    if (blocks.grays.empty())
        return;
    GrayInfo& g = plan.grays[static_cast<std::size_t>(blocks.grays[0])];
    check_cover(plan, g, axis);
    if (g.step_of_code.empty())
        build_step_table(g, ap.extent);
    build_coordinate_table(g);
    ap.coded = true;
    ap.method = UnwrapMethod::code;
    ap.gray = blocks.grays[0];
    std::string name = code_name(g.block);
    ap.name = name + "-code" + level_suffix(g.block);
}

// Phase + gray block of the same period: the code gives the fringe order.
void plan_gray_axis(Plan& plan, int axis, const AxisBlocks& blocks) {
    AxisPlan& ap = plan.axes[axis];
    GrayInfo& g = plan.grays[static_cast<std::size_t>(blocks.grays[0])];
    for (int p : blocks.phases)
        if (same_period(period_of(plan, p), g.block.period)) {
            g.phase = p;
            break;
        }
    if (g.phase < 0)
        refuse_sequence(plan, sequence_field(g.sequence_index, "period"),
                        "gray block on axis " + axis_letter(axis) + " indexes period " +
                            std::to_string(g.block.period) +
                            " but no phase block on that axis has it");
    check_cover(plan, g, axis);
    ap.method = UnwrapMethod::gray;
    ap.phases = {g.phase};
    ap.gray = blocks.grays[0];
    ap.name = code_name(g.block) + level_suffix(g.block);
}

// Several phase blocks: multi-period when the coarsest covers the extent,
// else heterodyne (two or three blocks whose beat covers it).
void plan_periods_axis(Plan& plan, int axis, const AxisBlocks& blocks) {
    AxisPlan& ap = plan.axes[axis];
    const std::string axis_name = axis_letter(axis);
    auto period = [&](int p) { return period_of(plan, p); };
    std::vector<int> sorted = blocks.phases;
    std::stable_sort(sorted.begin(), sorted.end(),
                     [&](int a, int b) { return period(a) < period(b); });
    for (std::size_t i = 1; i < sorted.size(); ++i)
        if (same_period(period(sorted[i]), period(sorted[i - 1])))
            refuse_sequence(
                plan,
                sequence_field(plan.phases[static_cast<std::size_t>(sorted[i])].sequence_index,
                               "period"),
                "axis " + axis_name + " has two phase blocks with the same period " +
                    std::to_string(period(sorted[i])));
    if (period(sorted.back()) + 1e-9 >= ap.extent) {
        ap.method = UnwrapMethod::multi_period;
        ap.name = "multi-period";
        ap.phases.assign(sorted.rbegin(), sorted.rend()); // coarse to fine
        return;
    }
    if (sorted.size() > 3)
        refuse_sequence(plan, "sequence",
                        "axis " + axis_name +
                            " has more than three phase blocks and none covers the projector "
                            "extent");
    std::vector<double> periods;
    for (int p : sorted)
        periods.push_back(period(p));
    ap.levels = heterodyne_levels(plan, periods, ap.extent, axis_name);
    ap.method = UnwrapMethod::heterodyne;
    ap.name = "heterodyne";
    ap.phases = sorted;
}

// One phase block: direct when it covers the extent, else made absolute by
// the axis's centerline block; without one the axis cannot be unwrapped.
void plan_single_phase_axis(Plan& plan, int axis, const AxisBlocks& blocks) {
    AxisPlan& ap = plan.axes[axis];
    const int phase = blocks.phases[0];
    if (period_of(plan, phase) + 1e-9 >= ap.extent) {
        ap.method = UnwrapMethod::direct;
        ap.name = "direct";
        ap.phases = {phase};
    } else if (blocks.centerlines.size() == 1) {
        ap.method = UnwrapMethod::centerline;
        ap.name = "centerline";
        ap.phases = {phase};
        ap.centerline = blocks.centerlines[0];
        plan.centerlines[static_cast<std::size_t>(blocks.centerlines[0])].phase = phase;
    } else {
        refuse_sequence(
            plan,
            sequence_field(plan.phases[static_cast<std::size_t>(phase)].sequence_index, "period"),
            "the phase block on axis " + axis_letter(axis) + " (period " +
                std::to_string(period_of(plan, phase)) +
                " px) is shorter than the projector extent and the sequence has no gray code, "
                "second period or centerline to unwrap it");
    }
}

// The axis's finest block (smallest period among those used) reports B and
// A; every block the method uses is decoded.
void use_axis_phases(Plan& plan, int axis) {
    AxisPlan& ap = plan.axes[axis];
    ap.report_phase = ap.phases[0];
    for (int p : ap.phases)
        if (period_of(plan, p) < period_of(plan, ap.report_phase))
            ap.report_phase = p;
    for (int p : ap.phases)
        plan.phases[static_cast<std::size_t>(p)].used = true;
}

} // namespace

// Code value -> code step (GrayInfo::step_of_code). Steps are numbered from
// the offset: step n covers [offset + n u, offset + (n + 1) u) (u = period, or
// period / 2 with the complementary plane); values whose step would start
// beyond the projector are the wrapped steps left of the offset (n - count).
void build_step_table(GrayInfo& g, double extent) {
    const GrayBlock& b = g.block;
    const double unit = b.complementary ? b.period / 2.0 : b.period;
    std::int64_t count = 1;
    for (int i = 0; i < g.planes; ++i)
        count *= b.levels;
    g.step_of_code.assign(static_cast<std::size_t>(count), kInvalidStep);
    g.max_step = -1e9f;
    for (std::int64_t n = 0; n < count; ++n) {
        std::int64_t value = 0, place = 1;
        for (int d = 0; d < g.planes; ++d, place *= b.levels)
            value += codeword_digit(b, g.planes, n, d) * place;
        double step = static_cast<double>(n);
        if (b.offset + step * unit > extent - 0.5)
            step -= static_cast<double>(count);
        const bool inside =
            b.offset + step * unit <= extent - 0.5 && b.offset + (step + 1.0) * unit > -0.5;
        if (!inside)
            continue;
        g.step_of_code[static_cast<std::size_t>(value)] = static_cast<float>(step);
        g.max_step = std::max(g.max_step, static_cast<float>(step));
    }
}

void plan_axis(Plan& plan, int axis) {
    AxisPlan& ap = plan.axes[axis];
    ap.extent = axis == 0 ? plan.projector.width : plan.projector.height;
    const AxisBlocks blocks = blocks_on_axis(plan, axis);
    check_one_code(plan, axis, blocks);
    if (plan_micro_axis(plan, axis, blocks))
        return;
    if (blocks.phases.empty()) {
        plan_code_only_axis(plan, axis, blocks);
        return;
    }
    ap.coded = true;
    if (blocks.grays.size() == 1)
        plan_gray_axis(plan, axis, blocks);
    else if (blocks.phases.size() >= 2)
        plan_periods_axis(plan, axis, blocks);
    else
        plan_single_phase_axis(plan, axis, blocks);
    use_axis_phases(plan, axis);
}

} // namespace fpp::detail
