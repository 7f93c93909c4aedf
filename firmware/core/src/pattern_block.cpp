#include "fpp/pattern_block.hpp"

namespace fpp {

namespace {
struct FrameCounter {
    int operator()(const WhiteBlock&) const { return 1; }
    int operator()(const BlackBlock&) const { return 1; }
    int operator()(const PhaseBlock& b) const {
        switch (b.shifting) {
        case PhaseShifting::two_plus_one:
            return 3;
        case PhaseShifting::modulated:
            return b.steps * b.carrier_steps;
        case PhaseShifting::standard:
            break;
        }
        return b.steps;
    }
    int operator()(const MicroPhaseBlock& b) const {
        return static_cast<int>(b.periods.size()) + 2;
    }
    int operator()(const GrayBlock& b) const {
        const int planes = b.bits + (b.complementary ? 1 : 0);
        return b.inverse ? 2 * planes : planes;
    }
    int operator()(const CenterlineBlock&) const { return 1; }
};
struct Namer {
    std::string operator()(const WhiteBlock&) const { return "white"; }
    std::string operator()(const BlackBlock&) const { return "black"; }
    std::string operator()(const PhaseBlock&) const { return "phase"; }
    std::string operator()(const GrayBlock&) const { return "gray"; }
    std::string operator()(const CenterlineBlock&) const { return "centerline"; }
    std::string operator()(const MicroPhaseBlock&) const { return "micro_phase"; }
};
} // namespace

int frame_count(const PatternBlock& block) {
    return std::visit(FrameCounter{}, block);
}

int frame_count(const Sequence& sequence) {
    int n = 0;
    for (const auto& b : sequence)
        n += frame_count(b);
    return n;
}

std::string pattern_name(const PatternBlock& block) {
    return std::visit(Namer{}, block);
}

} // namespace fpp
