#include "fpp/sequences.hpp"

#include <cmath>
#include <stdexcept>

namespace fpp {

namespace {

constexpr double kFinePeriod = 20.0; // projector pixels; 8 steps resolve it well
constexpr int kSteps = 8;

int extent_of(Axis axis, Size projector) {
    return axis == Axis::x ? projector.width : projector.height;
}

PhaseBlock phase(Axis axis, double period, int steps = kSteps, int shift_sign = 1) {
    PhaseBlock b;
    b.axis = axis;
    b.period = period;
    b.steps = steps;
    b.shift_sign = shift_sign;
    return b;
}

GrayBlock gray(Axis axis, Size projector, bool complementary, bool inverse) {
    GrayBlock b;
    b.axis = axis;
    b.period = kFinePeriod;
    b.bits = gray_bits_needed(kFinePeriod, extent_of(axis, projector));
    b.complementary = complementary;
    b.inverse = inverse;
    return b;
}

CenterlineBlock centerline(Axis axis, Size projector) {
    CenterlineBlock b;
    b.axis = axis;
    b.position = 0.5 * static_cast<double>(extent_of(axis, projector) - 1);
    b.width = 2.0;
    return b;
}

void add_phase_gray(Sequence& s, Axis axis, Size projector, bool complementary, bool inverse) {
    s.push_back(phase(axis, kFinePeriod));
    s.push_back(gray(axis, projector, complementary, inverse));
}

} // namespace

int gray_bits_needed(double period, int extent) {
    if (!(period > 0.0) || extent <= 0) {
        throw std::invalid_argument("gray_bits_needed: period and extent must be positive");
    }
    const double last_index = std::floor(static_cast<double>(extent - 1) / period);
    int bits = 1;
    while (bits < 30 && std::ldexp(1.0, bits) <= last_index)
        ++bits;
    return bits;
}

std::vector<std::string> standard_sequence_names() {
    return {"gray-xy",        "gray-x",       "plain-gray-x",  "inverse-gray-x",
            "multi-period-x", "heterodyne-x", "centerline-xy", "slstudio-like-x"};
}

Sequence standard_sequence(const std::string& name, Size projector) {
    if (projector.width <= 0 || projector.height <= 0) {
        throw std::invalid_argument("standard_sequence: projector size must be positive");
    }
    const auto width = static_cast<double>(projector.width);
    Sequence s;
    if (name == "gray-xy" || name == "gray-x") {
        s.push_back(WhiteBlock{});
        s.push_back(BlackBlock{});
        add_phase_gray(s, Axis::x, projector, true, false);
        if (name == "gray-xy")
            add_phase_gray(s, Axis::y, projector, true, false);
    } else if (name == "plain-gray-x") {
        s.push_back(WhiteBlock{});
        s.push_back(BlackBlock{});
        add_phase_gray(s, Axis::x, projector, false, false);
    } else if (name == "inverse-gray-x") {
        add_phase_gray(s, Axis::x, projector, true, true);
    } else if (name == "multi-period-x") {
        s.push_back(phase(Axis::x, kFinePeriod));
        s.push_back(phase(Axis::x, 160.0));
        s.push_back(phase(Axis::x, width));
    } else if (name == "heterodyne-x") {
        for (const double fringes : {64.0, 63.0, 56.0})
            s.push_back(phase(Axis::x, width / fringes));
    } else if (name == "centerline-xy") {
        s.push_back(WhiteBlock{});
        for (const Axis axis : {Axis::x, Axis::y}) {
            s.push_back(phase(axis, kFinePeriod));
            s.push_back(centerline(axis, projector));
        }
    } else if (name == "slstudio-like-x") {
        s.push_back(phase(Axis::x, width / 16.0, 3, -1));
        s.push_back(phase(Axis::x, width, 3, -1));
    } else {
        std::string known;
        for (const auto& n : standard_sequence_names())
            known += (known.empty() ? "" : ", ") + n;
        throw std::invalid_argument("unknown sequence name '" + name + "' (known: " + known + ")");
    }
    return s;
}

} // namespace fpp
