// The constants the row kernels need per axis, read once from the plan
// (unwrapping method, periods, code tables, saturation bits).
#include "decode_engine.hpp"

#include <cmath>
#include <cstdint>

namespace fpp::detail {

namespace {

std::uint8_t axis_bit(int axis) {
    return static_cast<std::uint8_t>(1u << axis);
}

} // namespace

AxisConstants axis_constants(const Plan& plan, int a) {
    AxisConstants c;
    const AxisPlan& ap = plan.axes[a];
    if (!ap.coded)
        return c;
    if (ap.method == UnwrapMethod::gray) {
        const GrayInfo& g = plan.grays[static_cast<std::size_t>(ap.gray)];
        const double period = g.block.period;
        const double unit = g.block.complementary ? period / 2.0 : period;
        c.gray.period = static_cast<float>(period);
        c.gray.unit = static_cast<float>(unit);
        c.gray.complementary = g.block.complementary;
        c.gray.max_code = static_cast<std::uint32_t>(std::floor((ap.extent - 1.0) / unit));
        // Code errors only happen where the camera pixel straddles a code edge
        // (blur and noise of about a projector pixel).
        c.gray.edge_band = static_cast<float>(std::min(period / 4.0, std::max(1.5, period / 8.0)));
        c.repair.period = static_cast<float>(period);
        c.repair.tolerance = static_cast<float>(period / 8.0);
        c.repair.max_slope = static_cast<float>(period / 4.0);
        if (!g.step_of_code.empty()) {
            c.gray.step_of_code = g.step_of_code.data();
            c.gray.offset = static_cast<float>(g.block.offset);
            c.gray.max_step = g.max_step;
            if (g.block.wrap)
                c.gray.wrap_span =
                    static_cast<float>(static_cast<double>(g.step_of_code.size()) * unit);
        }
    }
    if (ap.method == UnwrapMethod::code) {
        const GrayInfo& g = plan.grays[static_cast<std::size_t>(ap.gray)];
        const double unit = g.block.complementary ? g.block.period / 2.0 : g.block.period;
        c.gray.period = static_cast<float>(g.block.period);
        c.gray.unit = static_cast<float>(unit);
        c.gray.step_of_code = g.step_of_code.data();
        c.gray.offset = static_cast<float>(g.block.offset);
        c.gray.max_step = g.max_step;
        c.gray.resolve_carries =
            g.block.code == CodeKind::binary && g.block.levels == 2 && !g.block.complementary;
        c.gray.code_coordinate = g.code_coordinate.data();
        c.gray.code_count = static_cast<std::uint32_t>(g.step_of_code.size());
        c.gray.max_carry_run = kMaxCarryRun;
    }
    if (ap.method == UnwrapMethod::centerline) {
        const CenterlineInfo& cl = plan.centerlines[static_cast<std::size_t>(ap.centerline)];
        c.centerline.period =
            static_cast<float>(plan.phases[static_cast<std::size_t>(ap.phases[0])].block.period);
        c.centerline.position = cl.block.position;
        c.centerline.half_width = cl.block.width / 2.0;
        c.centerline.sat_bit = axis_bit(a);
        c.centerline.highest = static_cast<float>(ap.extent + 0.5);
    }
    if (ap.method == UnwrapMethod::heterodyne) {
        for (const auto& level : ap.levels) {
            HeterodyneStep s;
            s.period = static_cast<float>(level.period);
            for (int j = 0; j < 3; ++j)
                s.coef[j] = static_cast<float>(level.coef[j]);
            s.single = level.single;
            c.heterodyne.push_back(s);
        }
    }
    return c;
}

} // namespace fpp::detail
