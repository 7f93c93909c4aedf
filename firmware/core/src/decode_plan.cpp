#include "decode_plan.hpp"

#include "decode_weights.hpp"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <limits>
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
    if (b.shifting == PhaseShifting::two_plus_one && b.steps != 3)
        fail(name + ": 2+1 phase shifting has steps 3, got " + std::to_string(b.steps));
    if (b.steps < 3)
        fail(name + ": steps must be >= 3, got " + std::to_string(b.steps));
    if (!(std::isfinite(b.period) && b.period > 0))
        fail(name + ": period must be > 0");
    if (b.shift_sign != 1 && b.shift_sign != -1)
        fail(name + ": shift_sign must be +1 or -1");
    if (!std::isfinite(b.phase_offset))
        fail(name + ": phase_offset must be finite");
    if (b.shifting == PhaseShifting::modulated) {
        if (!(std::isfinite(b.carrier_period) && b.carrier_period > 0))
            fail(name + ": carrier_period must be > 0");
        if (b.carrier_steps < 3 || b.carrier_steps > 16)
            fail(name + ": carrier_steps must be in [3, 16], got " +
                 std::to_string(b.carrier_steps));
        if (b.steps > 16)
            fail(name + ": a modulated block has at most 16 steps, got " +
                 std::to_string(b.steps));
    }
}

void check_micro(const MicroPhaseBlock& b, int index) {
    const std::string name = block_name("micro_phase", index, b.axis == Axis::x ? 0 : 1);
    if (b.periods.size() < 2 || b.periods.size() > 16)
        fail(name + ": needs 2 to 16 periods, got " + std::to_string(b.periods.size()));
    for (double v : b.periods)
        if (!(std::isfinite(v) && v > 0))
            fail(name + ": every period must be > 0");
    if (b.shift_sign != 1 && b.shift_sign != -1)
        fail(name + ": shift_sign must be +1 or -1");
    if (!std::isfinite(b.phase_offset))
        fail(name + ": phase_offset must be finite");
    if (!b.extra_phase_offsets.empty() && b.extra_phase_offsets.size() + 1 != b.periods.size())
        fail(name + ": extra_phase_offsets needs one entry per period after the first (" +
             std::to_string(b.periods.size() - 1) + "), got " +
             std::to_string(b.extra_phase_offsets.size()));
    for (double v : b.extra_phase_offsets)
        if (!std::isfinite(v))
            fail(name + ": every extra_phase_offsets entry must be finite");
}

void check_gray(const GrayBlock& b, int index) {
    const std::string name = block_name("gray", index, b.axis == Axis::x ? 0 : 1);
    if (b.bits < 1)
        fail(name + ": bits must be >= 1");
    if (b.levels < 2)
        fail(name + ": levels must be >= 2, got " + std::to_string(b.levels));
    const int planes = b.bits + (b.complementary ? 1 : 0);
    if (std::pow(double(b.levels), double(planes)) > 65536.0)
        fail(name + ": levels^planes must be at most 65536 (16 bit planes), got " +
             std::to_string(b.levels) + "^" + std::to_string(planes));
    if (!(std::isfinite(b.period) && b.period > 0))
        fail(name + ": period must be > 0");
    if (!std::isfinite(b.offset))
        fail(name + ": offset must be finite");
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

void check_centerline(const CenterlineBlock& b, int index) {
    const std::string name = block_name("centerline", index, b.axis == Axis::x ? 0 : 1);
    if (!std::isfinite(b.position))
        fail(name + ": position must be finite");
    if (!(std::isfinite(b.width) && b.width > 0))
        fail(name + ": width must be > 0");
}

// A micro phase block as a phase block of its first period (3 shifted
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
    for (int k = 0; k < 3; ++k) {
        const double delta = 2.0 * std::numbers::pi * k / 3.0;
        info.cos_w.push_back(static_cast<float>(std::cos(delta)));
        info.sin_w.push_back(static_cast<float>(-m.shift_sign * std::sin(delta)));
    }
    info.offset_fraction = static_cast<float>(m.phase_offset / (2.0 * std::numbers::pi));
    return info;
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

    if (grays.size() > 1)
        fail("axis " + axis_name + " has more than one gray block");
    if (centerlines.size() > 1)
        fail("axis " + axis_name + " has more than one centerline block");
    auto period_of = [&](int p) { return plan.phases[static_cast<std::size_t>(p)].block.period; };
    // Appends, not operator+ on literals: GCC 12 warns falsely (-Wrestrict) there.
    auto code_name = [](const GrayBlock& b) {
        std::string name;
        if (b.offset != 0.0)
            name += "shifted-";
        if (b.inverse)
            name += "inverse-";
        if (b.complementary)
            name += "complementary-";
        name += b.code == CodeKind::binary ? "binary" : "gray";
        return name;
    };
    auto level_suffix = [](const GrayBlock& b) {
        std::string suffix;
        if (b.levels > 2) {
            suffix += '-';
            suffix += std::to_string(b.levels);
            suffix += "-level";
        }
        return suffix;
    };
    auto check_cover = [&](const GrayBlock& b) {
        const double cover = b.period * std::pow(double(b.levels), double(b.bits));
        if (cover + 1e-9 < ap.extent)
            fail("gray block on axis " + axis_name + " codes " + std::to_string(cover) +
                 " px, fewer than the projector extent of " + std::to_string(ap.extent) + " px");
    };
    for (int p : phases) {
        const PhaseInfo& info = plan.phases[static_cast<std::size_t>(p)];
        if (info.kind != PhaseKind::micro)
            continue;
        if (phases.size() > 1 || !grays.empty() || !centerlines.empty())
            fail("axis " + axis_name +
                 " has a micro_phase block and other coding blocks: micro phase shifting "
                 "codes its axis alone");
        ap.coded = true;
        ap.method = UnwrapMethod::micro;
        ap.name = "micro-phase";
        ap.phases = {p};
        ap.report_phase = p;
        plan.phases[static_cast<std::size_t>(p)].used = true;
        plan_micro_orders(plan.phases[static_cast<std::size_t>(p)], ap.extent);
        return;
    }
    if (phases.empty()) {
        if (!centerlines.empty())
            fail("axis " + axis_name + " has a centerline block but no phase block");
        if (grays.empty())
            return;
        // Code-only axis: the code alone gives the coordinate.
        GrayInfo& g = plan.grays[static_cast<std::size_t>(grays[0])];
        check_cover(g.block);
        if (g.step_of_code.empty())
            build_step_table(g, ap.extent);
        build_coordinate_table(g);
        ap.coded = true;
        ap.method = UnwrapMethod::code;
        ap.gray = grays[0];
        std::string name = code_name(g.block);
        ap.name = name + "-code" + level_suffix(g.block);
        return;
    }
    ap.coded = true;

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
        check_cover(g.block);
        ap.method = UnwrapMethod::gray;
        ap.phases = {g.phase};
        ap.gray = grays[0];
        ap.name = code_name(g.block) + level_suffix(g.block);
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
            info.frames = frame_count(block);
            info.axis = p->axis == Axis::x ? 0 : 1;
            if (p->shifting == PhaseShifting::two_plus_one)
                info.kind = PhaseKind::two_plus_one;
            if (p->shifting == PhaseShifting::modulated) {
                info.kind = PhaseKind::modulated;
                for (int j = 0; j < p->carrier_steps; ++j) {
                    const double delta = 2.0 * std::numbers::pi * j / p->carrier_steps;
                    info.carrier_cos.push_back(static_cast<float>(std::cos(delta)));
                    info.carrier_sin.push_back(static_cast<float>(std::sin(delta)));
                }
            }
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
        } else if (const auto* m = std::get_if<MicroPhaseBlock>(&block)) {
            check_micro(*m, index);
            plan.phases.push_back(micro_info(*m, frame, frame_count(block)));
        } else if (const auto* g = std::get_if<GrayBlock>(&block)) {
            check_gray(*g, index);
            GrayInfo info;
            info.block = *g;
            info.first_frame = frame;
            info.axis = g->axis == Axis::x ? 0 : 1;
            info.planes = g->bits + (g->complementary ? 1 : 0);
            for (int k = 0; k < info.planes; ++k) {
                const int position =
                    g->order == DigitOrder::msb_first ? info.planes - 1 - k : k;
                info.weight.push_back(static_cast<std::uint16_t>(
                    std::lround(std::pow(double(g->levels), double(position)))));
            }
            // fpp-capture/1's plain Gray keeps its vectorised gray_to_binary.
            if (g->code != CodeKind::gray || g->levels != 2 || g->offset != 0.0 || g->wrap)
                build_step_table(info, g->axis == Axis::x ? projector.width : projector.height);
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
    if (plan.phases.empty() && plan.grays.empty())
        fail("the sequence has no phase block (nor micro_phase or gray block), so no axis can "
             "be decoded");

    plan_axis(plan, 0);
    plan_axis(plan, 1);
    if (!plan.axes[0].coded && !plan.axes[1].coded)
        fail("no axis can be decoded");

    const bool have_white_black = plan.white_frame >= 0 && plan.black_frame >= 0;
    for (std::size_t gi = 0; gi < plan.grays.size(); ++gi) {
        GrayInfo& g = plan.grays[gi];
        const std::string name = block_name("gray", static_cast<int>(gi), g.axis) + " (" +
                                 std::to_string(g.block.levels) + " levels)";
        if (g.block.wrap && (g.phase < 0 || g.block.complementary || g.block.levels != 2))
            fail(name + ": wrap needs a two-level code without the complementary plane that "
                        "indexes a phase block (the phase tells its last step from its first)");
        if (g.block.levels > 2) {
            if (g.block.inverse)
                fail(name + ": inverse frames are not defined for more than 2 levels");
            if (!have_white_black)
                fail(name + ": multi-level digits need white and black frames in the sequence");
            g.threshold = GrayThreshold::white_black;
            plan.uses_levels = true;
        } else if (g.block.inverse) {
            g.threshold = GrayThreshold::inverse;
        } else if (have_white_black) {
            g.threshold = GrayThreshold::white_black;
        } else if (g.phase >= 0) {
            g.threshold = GrayThreshold::phase_mean;
        } else {
            fail(name + ": a code-only axis needs inverse frames or white and black frames "
                        "to threshold its planes");
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
        s.frames = p.frames;
        s.index = b;
        s.sat_bits = static_cast<std::uint8_t>(1u << p.axis);
        steps.push_back(s);
    }
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
                s.trigger = std::max(s.frame, white_black_ready);
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
