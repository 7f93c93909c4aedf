// The pattern sequences of SLStudio, SLMaster and OpenCV's structured_light
// module, as capture-set blocks. Each convention and its source is in
// firmware/core/formats/imports.md; the comments say only what is needed to
// check the mapping against our formulas (fpp/patterns.hpp).

#include "fpp/calib/capture_import.hpp"

#include "fpp/enum_names.hpp"
#include "fpp/error.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

namespace fpp::calib {

namespace fs = std::filesystem;

constexpr EnumName<ImportTool> kImportToolNames[] = {
    {ImportTool::slstudio, "slstudio"},
    {ImportTool::slmaster, "slmaster"},
    {ImportTool::opencv, "opencv"},
};

ImportTool parse_import_tool(const std::string& name) {
    return parse_name(kImportToolNames, "tool", name);
}

const char* to_string(ImportTool tool) {
    return name_of(kImportToolNames, tool);
}

namespace {

constexpr double kPi = std::numbers::pi;

struct Axes {
    bool x = false;
    bool y = false;
};

Axes axes_of(const ImportOptions& o, const fs::path& origin, bool y_allowed) {
    Axes a;
    if (o.direction == "x")
        a.x = true;
    else if (o.direction == "y")
        a.y = true;
    else if (o.direction == "both")
        a.x = a.y = true;
    else
        throw InputError(origin, "direction",
                         "unknown direction '" + o.direction + "' (x, y, both)");
    if (a.y && !y_allowed)
        throw InputError(origin, "direction",
                         o.codec + " codes columns only (x): the tool has no other direction");
    return a;
}

int extent(const ImportOptions& o, Axis axis) {
    return axis == Axis::x ? o.projector.width : o.projector.height;
}

// SLStudio's fringes: I = 1/2 (1 + cos(2 pi i / pitch - 2 pi k / N)), i the
// projector pixel, so shift_sign -1 and no offset.
PhaseBlock slstudio_phase(Axis axis, double period, int steps) {
    PhaseBlock b;
    b.axis = axis;
    b.period = period;
    b.steps = steps;
    b.shift_sign = -1;
    return b;
}

int positive_option(int value, const char* name, const fs::path& origin) {
    if (value < 1)
        throw InputError(origin, name, "must be a positive integer, got " + std::to_string(value));
    return value;
}

Sequence slstudio_sequence(const ImportOptions& o, const fs::path& origin) {
    Sequence s;
    const std::string& c = o.codec;
    if (c == "2x3" || c == "nstep") {
        const Axes axes = axes_of(o, origin, true);
        const bool nstep = c == "nstep";
        const int phases = nstep ? positive_option(o.slstudio_nstep_phases, "nstep-phases", origin)
                                 : positive_option(o.slstudio_2x3_phases, "phases", origin);
        const int steps =
            nstep ? positive_option(o.slstudio_nstep_steps, "nstep-steps", origin) : 3;
        for (Axis axis : {Axis::x, Axis::y}) {
            if (!(axis == Axis::x ? axes.x : axes.y))
                continue;
            const double e = extent(o, axis);
            s.push_back(slstudio_phase(axis, e / phases, steps)); // pitch = extent / nPhases
            s.push_back(slstudio_phase(axis, e, 3));              // the one-period cue
        }
    } else if (c == "3") {
        axes_of(o, origin, false);
        s.push_back(slstudio_phase(Axis::x, o.projector.width, 3));
    } else if (c == "2p1") {
        // Frames cos(theta), cos(theta - pi/2) = sin(theta), flat 1/2 with
        // theta = 2 pi x / width. Ours (two_plus_one): 1/2 + 1/2 s sin(phi),
        // 1/2 + 1/2 cos(phi), 1/2 with phi = theta + phase_offset: s = -1 and
        // phase_offset = -pi/2 give exactly SLStudio's frames.
        axes_of(o, origin, false);
        PhaseBlock b = slstudio_phase(Axis::x, o.projector.width, 3);
        b.shifting = PhaseShifting::two_plus_one;
        b.phase_offset = -kPi / 2;
        s.push_back(b);
    } else if (c == "modulated") {
        // 3 x 3 frames, fringe shift outer, carrier shift inner; fringe
        // period width / nPhaseX (24), carrier period height / nPhaseY (16)
        // along y; then a 3-step one-period cue. SLStudio shifts its carrier
        // by -2 pi k / 3, ours by +2 pi k / 3: import_capture lists carrier
        // frames 1 and 2 of each triple swapped (import_frame_order), which
        // makes them exact.
        axes_of(o, origin, false);
        const int fringes =
            positive_option(o.slstudio_modulated_phases_x, "modulated-phases", origin);
        const int carriers =
            positive_option(o.slstudio_modulated_phases_y, "modulated-carrier-phases", origin);
        PhaseBlock b = slstudio_phase(Axis::x, o.projector.width / double(fringes), 3);
        b.shifting = PhaseShifting::modulated;
        b.carrier_period = o.projector.height / double(carriers);
        b.carrier_steps = 3;
        s.push_back(b);
        s.push_back(slstudio_phase(Axis::x, o.projector.width, 3));
    } else if (c == "graycode") {
        // White, black, then the first N planes (MSB first) of the Gray code
        // of the pixel index with ceil(log2(extent)) bits: the Gray code of
        // floor(p / 2^(bits - N)), no inverse frames.
        const Axes axes = axes_of(o, origin, true);
        s.push_back(WhiteBlock{});
        s.push_back(BlackBlock{});
        for (Axis axis : {Axis::x, Axis::y}) {
            if (!(axis == Axis::x ? axes.x : axes.y))
                continue;
            const int planes =
                positive_option(axis == Axis::x ? o.slstudio_gray_bits_x : o.slstudio_gray_bits_y,
                                axis == Axis::x ? "gray-bits-x" : "gray-bits-y", origin);
            const int bits = static_cast<int>(std::ceil(std::log2(double(extent(o, axis)))));
            if (planes > bits)
                throw InputError(origin, axis == Axis::x ? "gray-bits-x" : "gray-bits-y",
                                 std::to_string(planes) + " planes but the projector's " +
                                     std::to_string(extent(o, axis)) + " pixels need only " +
                                     std::to_string(bits));
            GrayBlock g;
            g.axis = axis;
            g.bits = planes;
            g.period = std::ldexp(1.0, bits - planes);
            s.push_back(g);
        }
    } else if (c == "micro") {
        // CodecPhaseShiftMicro (F = 10): 3 frames of pitch 75.02 shifted by
        // +2 pi k / 3 in our convention (SLStudio's phase -2 pi k / 3), then
        // one frame per other pitch, inverted (phase pi) at every odd index.
        axes_of(o, origin, false);
        MicroPhaseBlock b;
        b.axis = Axis::x;
        b.periods = {75.02, 70.00, 71.32, 72.47, 73.72, 76.23, 77.35, 78.40, 79.22, 80.00};
        for (std::size_t i = 1; i < b.periods.size(); ++i)
            b.extra_phase_offsets.push_back(i % 2 == 1 ? kPi : 0.0);
        s.push_back(b);
    } else {
        throw InputError(origin, "codec",
                         "unknown SLStudio codec '" + c +
                             "' (2x3, 3, nstep, 2p1, modulated, graycode, micro)");
    }
    return s;
}

// SLMaster's fringes: 127.5 + 127.5 cos(2 pi frac(p / P) - pi + 2 pi k / N).
PhaseBlock slmaster_phase(Axis axis, double period, int steps) {
    PhaseBlock b;
    b.axis = axis;
    b.period = period;
    b.steps = steps;
    b.shift_sign = 1;
    b.phase_offset = -kPi;
    return b;
}

// Three fringe counts F, F - 6, F - 11 of `steps` frames each, F first;
// periods extent / count, not rounded (threeFrequencyHeterodynePattern).
Sequence slmaster_three_frequency(const ImportOptions& o, Axis axis, int steps,
                                  const fs::path& origin) {
    const int e = extent(o, axis);
    const int highest = o.fringes != 0 ? o.fringes : 32; // SLMaster's default nbrOfPeriods
    if (highest - 11 < 1 || e / double(highest) < 3)
        throw InputError(origin, "fringes",
                         "SLMaster's three-frequency code shows nbrOfPeriods, nbrOfPeriods - 6 "
                         "and nbrOfPeriods - 11 fringes: nbrOfPeriods must be 12 .. " +
                             std::to_string(e / 3) + " (periods of at least 3 px), got " +
                             std::to_string(highest));
    Sequence s;
    for (const int count : {highest, highest - 6, highest - 11})
        s.push_back(slmaster_phase(axis, double(e) / count, steps));
    return s;
}

// 3 (or any odd count of) phase frames, then log4(count) frames of a
// reflected 4-level Gray code (levels 0, 85, 170, 255), most significant
// first, in blocks of extent / 4^(i+1): no white or black frame, the digits
// scaled by the phase frames (interzoneSinusFourGrayscalePattern).
Sequence slmaster_interzone(const ImportOptions& o, Axis axis, int steps, const fs::path& origin) {
    const int e = extent(o, axis);
    const int fringes = o.fringes != 0 ? o.fringes : 16; // SLMaster's default nbrOfPeriods
    int digits = 0;
    for (int c = fringes; c > 1 && c % 4 == 0; c /= 4)
        ++digits;
    if (fringes < 4 || std::lround(std::pow(4.0, digits)) != fringes)
        throw InputError(origin, "fringes",
                         "SLMaster's interzone code needs a fringe count (nbrOfPeriods) that is "
                         "a power of 4 (it shows log4(count) four-level frames); got " +
                             std::to_string(fringes));
    if (e % fringes != 0)
        throw InputError(origin, "fringes",
                         "the projector's " + std::to_string(e) + " pixels are not a multiple of " +
                             std::to_string(fringes) +
                             ": SLMaster's four-level blocks (extent / 4^k each) then do not "
                             "follow its fringes");
    if (steps % 2 == 0)
        throw InputError(origin, "steps",
                         "SLMaster's interzone code needs an odd shiftTime, got " +
                             std::to_string(steps));
    GrayBlock gray;
    gray.axis = axis;
    gray.period = e / fringes;
    gray.bits = digits;
    gray.levels = 4;
    return {slmaster_phase(axis, e / fringes, steps), gray};
}

Sequence slmaster_sequence(const ImportOptions& o, const fs::path& origin) {
    const bool three = o.codec == "three-frequency", interzone = o.codec == "interzone";
    if (o.codec != "complementary" && o.codec != "shift-gray" && !three && !interzone)
        throw InputError(origin, "codec",
                         "unknown SLMaster codec '" + o.codec +
                             "' (complementary, shift-gray, three-frequency, interzone)");
    const Axes axes = axes_of(o, origin, true);
    if (axes.x && axes.y)
        throw InputError(origin, "direction",
                         "SLMaster codes one axis per capture (its `horizontal` flag): x or y");
    const Axis axis = axes.x ? Axis::x : Axis::y;
    const int e = extent(o, axis);
    const int steps = o.steps != 0 ? o.steps : interzone ? 3 : 4; // SLMaster's shiftTime defaults
    if (steps < 3)
        throw InputError(origin, "steps",
                         "SLMaster's shiftTime must be 3 or more, got " + std::to_string(steps));
    if (three || interzone) {
        if (o.period > 0)
            throw InputError(origin, "period",
                             "give --fringes (nbrOfPeriods) for SLMaster's " + o.codec + " code");
        return three ? slmaster_three_frequency(o, axis, steps, origin)
                     : slmaster_interzone(o, axis, steps, origin);
    }
    int fringes = o.fringes;
    if (fringes == 0 && o.period > 0) {
        const double f = e / o.period;
        if (std::fabs(f - std::round(f)) > 1e-9)
            throw InputError(origin, "period",
                             "SLMaster's period is the extent over the fringe count; " +
                                 std::to_string(e) + " / " + std::to_string(o.period) +
                                 " is not a whole number of fringes");
        fringes = static_cast<int>(std::lround(f));
    }
    if (fringes < 1 || (fringes & (fringes - 1)) != 0)
        throw InputError(
            origin, "fringes",
            "SLMaster needs a fringe count (nbrOfPeriods) that is a power of 2 "
            "(it shows log2(count) Gray planes); got " +
                std::to_string(fringes) +
                (o.fringes == 0 && o.period <= 0 ? " (give --fringes or --period)" : ""));
    if (e % (2 * fringes) != 0)
        throw InputError(origin, "fringes",
                         "the projector's " + std::to_string(e) +
                             " pixels are not a multiple of "
                             "2 x " +
                             std::to_string(fringes) +
                             ": SLMaster's Gray planes (extent / 2^k each) then do not follow "
                             "its fringes (extent / count, rounded down)");
    const int period = e / fringes; // SLMaster: width / nbrOfPeriods, integer division
    const int bits = static_cast<int>(std::lround(std::log2(double(fringes))));
    const PhaseBlock phase = slmaster_phase(axis, period, steps);
    GrayBlock gray;
    gray.axis = axis;
    gray.period = period;
    gray.bits = bits;
    if (o.codec == "complementary") {
        gray.complementary = true; // log2(count) + 1 planes, the last of half-period steps
    } else {
        // log2(count) planes moved by half a period towards 0, cyclically:
        // code step n covers [n P - P/2, (n + 1) P - P/2), and the last half
        // period shows step `count` with step 0's code again (wrap), which
        // the phase tells apart.
        gray.offset = -period / 2.0;
        gray.wrap = true;
    }
    return {phase, gray};
}

// SinusoidalPattern::generate() gives the same three patterns for FTP, PSP
// and FAPS: I_k = 127.5 (1 + sin(2 pi p / P + 2 pi k / 3)), p the pixel index
// along the coded axis, P = extent / nbrOfPeriods in integer division.
// sin t = cos(t - pi/2): shift_sign +1, phase_offset -pi/2. The module
// unwraps spatially, relative to nothing; an absolute coordinate needs a set
// with one period across the axis (or sets the decoder can unwrap from).
Sequence opencv_sinusoidal(const ImportOptions& o, const fs::path& origin) {
    const Axes axes = axes_of(o, origin, true);
    if (axes.x && axes.y)
        throw InputError(origin, "direction",
                         "OpenCV's SinusoidalPattern codes one axis per set (its `horizontal` "
                         "flag): x or y");
    const Axis axis = axes.x ? Axis::x : Axis::y;
    const int e = extent(o, axis);
    if (o.fringe_counts.empty())
        throw InputError(origin, "fringe-counts",
                         "give nbrOfPeriods of each set of three patterns, in capture order "
                         "(e.g. 1,4,16)");
    Sequence s;
    for (const int count : o.fringe_counts) {
        if (count < 1 || e / count < 3)
            throw InputError(origin, "fringe-counts",
                             std::to_string(count) + " fringes across " + std::to_string(e) +
                                 " pixels: need 1 .. " + std::to_string(e / 3) +
                                 " (periods of at least 3 pixels)");
        PhaseBlock b;
        b.axis = axis;
        b.period = e / count; // integer division, as the module does
        b.steps = 3;
        b.shift_sign = 1;
        b.phase_offset = -kPi / 2;
        s.push_back(b);
    }
    if (o.fringe_counts.size() == 1 && o.fringe_counts[0] != 1)
        throw InputError(origin, "fringe-counts",
                         "one set of " + std::to_string(o.fringe_counts[0]) +
                             " fringes tells the position within a fringe only (OpenCV unwraps "
                             "it relative to nothing); capture a set with nbrOfPeriods 1 too "
                             "(and sets between for a large ratio) and list them all");
    return s;
}

Sequence opencv_sequence(const ImportOptions& o, const fs::path& origin) {
    if (o.codec == "sinusoidal")
        return opencv_sinusoidal(o, origin);
    if (o.codec != "graycode")
        throw InputError(origin, "codec",
                         "unknown OpenCV structured_light pattern '" + o.codec +
                             "' (graycode, sinusoidal)");
    if (o.direction != "both")
        throw InputError(origin, "direction",
                         "OpenCV's GrayCodePattern codes columns and rows: direction both");
    // ceil(log2(extent)) planes per axis, columns then rows, MSB first, each
    // followed by its inverse; 1 = white; period 1 px.
    Sequence s;
    auto code = [&](Axis axis) {
        GrayBlock g;
        g.axis = axis;
        g.period = 1;
        g.bits = static_cast<int>(std::ceil(std::log2(double(extent(o, axis)))));
        g.inverse = true;
        return g;
    };
    if (o.shadow_images == "first") {
        s.push_back(WhiteBlock{});
        s.push_back(BlackBlock{});
    } else if (o.shadow_images != "last" && o.shadow_images != "none") {
        throw InputError(origin, "shadow-images",
                         "unknown placement '" + o.shadow_images + "' (last, first, none)");
    }
    s.push_back(code(Axis::x));
    s.push_back(code(Axis::y));
    if (o.shadow_images == "last") {
        s.push_back(WhiteBlock{});
        s.push_back(BlackBlock{});
    }
    return s;
}

} // namespace

std::vector<int> import_frame_order(const ImportOptions& o, const Sequence& sequence) {
    std::vector<int> order;
    for (int i = 0; i < frame_count(sequence); ++i)
        order.push_back(i);
    if (o.tool == ImportTool::slstudio && o.codec == "modulated") {
        // Manifest frame shift * 3 + c is SLStudio's frame shift * 3 + (3 - c) % 3.
        for (int shift = 0; shift < 3; ++shift)
            std::swap(order[std::size_t(shift * 3 + 1)], order[std::size_t(shift * 3 + 2)]);
    }
    return order;
}

Sequence import_sequence(const ImportOptions& o, const fs::path& origin) {
    if (o.projector.width < 2 || o.projector.height < 2 || o.projector.width > 65535 ||
        o.projector.height > 65535)
        throw InputError(origin, "projector",
                         "projector size " + std::to_string(o.projector.width) + "x" +
                             std::to_string(o.projector.height) + " outside 2..65535");
    switch (o.tool) {
    case ImportTool::slstudio:
        return slstudio_sequence(o, origin);
    case ImportTool::slmaster:
        return slmaster_sequence(o, origin);
    case ImportTool::opencv:
        return opencv_sequence(o, origin);
    }
    throw InputError(origin, "tool", "unknown tool");
}

} // namespace fpp::calib
