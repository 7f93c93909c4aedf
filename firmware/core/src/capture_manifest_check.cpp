#include "capture_manifest_check.hpp"

#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>

namespace fpp::capture_check {

namespace {

namespace fs = std::filesystem;
using yaml_fields::child;
using yaml_fields::format_real;
using yaml_fields::item;

std::string int_text(std::int64_t v) {
    return std::to_string(v);
}

bool same_period(double a, double b) {
    return std::abs(a - b) <= 1e-9 * std::max(a, b);
}

void check_period(const Checker& check, const std::string& field, double period) {
    if (!std::isfinite(period))
        check.fail(field, "non-finite number");
    if (!(period > 0.0)) {
        check.fail(field, "must be > 0 projector pixels, got " + format_real(period));
    }
}

void check_sign_and_offset(const Checker& check, std::size_t i, int shift_sign,
                           double phase_offset) {
    if (shift_sign != 1 && shift_sign != -1) {
        check.fail(block_field(i, "shift_sign"),
                   "must be 1 or -1, got " + std::to_string(shift_sign));
    }
    if (!std::isfinite(phase_offset))
        check.fail(block_field(i, "phase_offset"), "non-finite number");
}

void check_phase(const PhaseBlock& p, std::size_t i, const Checker& check) {
    check_period(check, block_field(i, "period"), p.period);
    if (p.shifting == PhaseShifting::two_plus_one && p.steps != 3) {
        check.fail(block_field(i, "steps"),
                   "shifting two_plus_one has exactly 3 frames (steps 3 or absent), got " +
                       std::to_string(p.steps));
    }
    if (p.steps < 3) {
        check.fail(block_field(i, "steps"),
                   "must be at least 3 (N >= 3), got " + std::to_string(p.steps));
    }
    check_sign_and_offset(check, i, p.shift_sign, p.phase_offset);
    if (p.shifting == PhaseShifting::modulated) {
        check_period(check, block_field(i, "carrier_period"), p.carrier_period);
        if (p.carrier_steps < 3) {
            check.fail(block_field(i, "carrier_steps"),
                       "must be at least 3, got " + std::to_string(p.carrier_steps));
        }
    } else if (p.carrier_period != 0.0 || p.carrier_steps != 0) {
        check.fail(block_field(i, p.carrier_period != 0.0 ? "carrier_period" : "carrier_steps"),
                   std::string("only with shifting: modulated (this block is ") +
                       to_string(p.shifting) + ")");
    }
}

void check_micro_phase(const MicroPhaseBlock& m, std::size_t i, const Checker& check) {
    if (m.periods.size() < 2) {
        check.fail(block_field(i, "periods"),
                   "must list at least 2 periods, got " + std::to_string(m.periods.size()));
    }
    for (std::size_t k = 0; k < m.periods.size(); ++k) {
        const std::string field = item(block_field(i, "periods"), k);
        check_period(check, field, m.periods[k]);
        for (std::size_t j = 0; j < k; ++j) {
            if (m.periods[j] == m.periods[k]) {
                check.fail(field, format_real(m.periods[k]) + " is also periods[" +
                                      std::to_string(j) + "] (periods must be distinct)");
            }
        }
    }
    check_sign_and_offset(check, i, m.shift_sign, m.phase_offset);
    // Empty: every other frame at phase_offset alone.
    if (!m.extra_phase_offsets.empty() && m.extra_phase_offsets.size() + 1 != m.periods.size()) {
        check.fail(block_field(i, "extra_phase_offsets"),
                   "must list one offset per period after the first (" +
                       std::to_string(m.periods.size() > 0 ? m.periods.size() - 1 : 0) + "), got " +
                       std::to_string(m.extra_phase_offsets.size()));
    }
    for (std::size_t k = 0; k < m.extra_phase_offsets.size(); ++k) {
        if (!std::isfinite(m.extra_phase_offsets[k]))
            check.fail(item(block_field(i, "extra_phase_offsets"), k), "non-finite number");
    }
}

// levels^digits, or -1 above 2^31.
std::int64_t code_count(int levels, int digits) {
    std::int64_t count = 1;
    for (int d = 0; d < digits; ++d) {
        count *= levels;
        if (count > (std::int64_t{1} << 31))
            return -1;
    }
    return count;
}

void check_gray(const Sequence& sequence, const GrayBlock& g, std::size_t i, const Checker& check,
                int version) {
    check_period(check, block_field(i, "period"), g.period);
    if (g.bits < 1 || g.bits > kMaxGrayBits) {
        check.fail(block_field(i, "bits"), "must be between 1 and " + std::to_string(kMaxGrayBits) +
                                               ", got " + std::to_string(g.bits));
    }
    if (g.levels < 2) {
        check.fail(block_field(i, "levels"), "must be at least 2, got " + std::to_string(g.levels));
    }
    const std::int64_t count = code_count(g.levels, g.bits);
    if (count < 0 || count > (std::int64_t{1} << kMaxGrayBits)) {
        check.fail(block_field(i, "levels"), "levels^bits must be at most 2^30, got " +
                                                 std::to_string(g.levels) + "^" +
                                                 std::to_string(g.bits));
    }
    if (!std::isfinite(g.offset))
        check.fail(block_field(i, "offset"), "non-finite number");
    if (g.complementary && (g.code != CodeKind::gray || g.levels != 2)) {
        check.fail(block_field(i, "complementary"),
                   "only with code gray and levels 2 (the extra plane is a binary Gray plane)");
    }
    bool white = false;
    bool black = false;
    for (const PatternBlock& other : sequence) {
        white = white || std::holds_alternative<WhiteBlock>(other);
        black = black || std::holds_alternative<BlackBlock>(other);
    }
    if (g.levels > 2 && !(white && black) && !gray_indexes_phase(sequence, g)) {
        check.fail(block_field(i, "levels"),
                   "a code of " + std::to_string(g.levels) +
                       " levels needs a white and a black block in the sequence, or a phase "
                       "block of its period on its axis, to scale its levels (inverse frames "
                       "cannot)");
    }
    if (g.wrap && (g.complementary || g.levels != 2)) {
        check.fail(block_field(i, "wrap"),
                   "only for a two-level code without the complementary plane (the phase tells "
                   "the wrapped step from the first by its half of the period)");
    }
    if (gray_indexes_phase(sequence, g))
        return;
    if (g.wrap) {
        check.fail(block_field(i, "wrap"),
                   std::string("a wrapping code needs a phase block of its period on axis ") +
                       to_string(g.axis) +
                       " to tell its last step from its first (a code-only block cannot)");
    }

    // A code-only block: it codes the axis by itself.
    std::string periods;
    for (const PatternBlock& other : sequence) {
        const auto* q = std::get_if<PhaseBlock>(&other);
        if (q && q->axis == g.axis) {
            periods += (periods.empty() ? "" : ", ") + format_real(q->period);
        }
    }
    const std::string why = format_real(g.period) +
                            " is not the period of any phase block on axis " + to_string(g.axis) +
                            " (" +
                            (periods.empty() ? std::string("there is no phase block on this axis")
                                             : "phase periods on this axis: " + periods) +
                            ")";
    if (version < 2) {
        check.fail(block_field(i, "period"),
                   why + "; in fpp-capture/1 a gray block indexes a phase block's periods (a "
                         "gray block that codes the axis by itself needs format: fpp-capture/2)");
    }
    if (!g.inverse && !(white && black)) {
        check.fail(block_field(i, "period"),
                   why + ", so the block codes the axis by itself and needs a threshold "
                         "reference: inverse: true, or a white and a black block in the sequence");
    }
}

// Code steps n = floor(scale (p - offset) / period) of projector pixel
// centres p = 0 .. extent - 1 must be fewer than the code numbers.
void check_gray_coverage(const GrayBlock& g, std::size_t i, Size projector, const Checker& check) {
    const int extent = g.axis == Axis::x ? projector.width : projector.height;
    const double scale = g.complementary ? 2.0 : 1.0;
    const int digits = g.bits + (g.complementary ? 1 : 0);
    const double first = std::floor(scale * (0.0 - g.offset) / g.period);
    const double last = std::floor(scale * (static_cast<double>(extent - 1) - g.offset) / g.period);
    const double steps = last - first + 1.0;
    const std::int64_t count = code_count(g.levels, digits);
    // wrap: the last step shows the first one's code again.
    if (steps <= static_cast<double>(count) + (g.wrap ? 1.0 : 0.0))
        return;
    int needed = g.bits;
    for (; needed < 62; ++needed) {
        const std::int64_t numbered = code_count(g.levels, needed + (digits - g.bits));
        if (numbered < 0 || static_cast<double>(numbered) >= steps)
            break;
    }
    const char* unit = g.complementary ? " half code steps " : " code steps ";
    check.fail(block_field(i, "bits"),
               std::to_string(g.bits) + " bits of " + std::to_string(g.levels) + " levels number " +
                   int_text(count) + unit + "(0 to " + int_text(count - 1) + "), but the " +
                   std::to_string(extent) + " projector " +
                   (g.axis == Axis::x ? "columns" : "rows") + " span" + unit + format_real(first) +
                   " to " + format_real(last) + " (" + format_real(steps) + ") at period " +
                   format_real(g.period) + " and offset " + format_real(g.offset) + ": at least " +
                   std::to_string(needed) + " bits are needed");
}

// A path relative to the capture folder that stays inside it.
void check_relative_name(const std::string& name, const std::string& field, const Checker& check) {
    if (name.empty())
        check.fail(field, "empty file name");
    const fs::path p(name);
    if (p.is_absolute())
        check.fail(field, "'" + name + "' must be relative to the capture folder");
    for (const auto& part : p) {
        if (part == "..")
            check.fail(field, "'" + name + "' must stay inside the capture folder");
    }
    if (p.filename().empty() || p.filename() == ".") {
        check.fail(field, "'" + name + "' is not a file name");
    }
    if (p.lexically_normal() == fs::path(kManifestName)) {
        check.fail(field, "'" + name + "' is the manifest's own name");
    }
}

std::string normal_name(const std::string& name) {
    return fs::path(name).lexically_normal().string();
}

void check_metadata_text(const std::string& text, const Checker& check) {
    YAML::Node node;
    try {
        node = YAML::Load(text);
    } catch (const YAML::Exception& e) {
        check.fail("metadata", "not valid YAML: " + e.msg);
    }
    if (!node.IsNull() && !node.IsMap())
        check.fail("metadata", "must be a map");
}

} // namespace

void Checker::fail(const std::string& field, const std::string& message) const {
    throw InputError(origin_, field, message + where(field));
}

std::string Checker::where(std::string field) const {
    if (!lines_)
        return {};
    while (!field.empty()) {
        if (auto it = lines_->find(field); it != lines_->end()) {
            return " (line " + std::to_string(it->second) + ")";
        }
        const auto cut = field.find_last_of(".[");
        if (cut == std::string::npos)
            break;
        field.erase(cut);
    }
    return {};
}

std::string block_field(std::size_t index, const char* key) {
    return child(item("sequence", index), key);
}

bool gray_indexes_phase(const Sequence& sequence, const GrayBlock& gray) {
    return std::any_of(sequence.begin(), sequence.end(), [&](const PatternBlock& b) {
        const auto* q = std::get_if<PhaseBlock>(&b);
        return q && q->axis == gray.axis && same_period(q->period, gray.period);
    });
}

bool uses_version_2(const Sequence& sequence) {
    for (const PatternBlock& block : sequence) {
        if (std::holds_alternative<MicroPhaseBlock>(block))
            return true;
        if (const auto* p = std::get_if<PhaseBlock>(&block)) {
            if (p->shifting != PhaseShifting::standard || p->carrier_period != 0.0 ||
                p->carrier_steps != 0) {
                return true;
            }
        } else if (const auto* g = std::get_if<GrayBlock>(&block)) {
            if (g->code != CodeKind::gray || g->levels != 2 || g->order != DigitOrder::msb_first ||
                g->offset != 0.0 || g->wrap || !gray_indexes_phase(sequence, *g)) {
                return true;
            }
        }
    }
    return false;
}

bool uses_version_2(const CaptureManifest& manifest) {
    return manifest.bit_depth != 0 || uses_version_2(manifest.sequence);
}

void check_sequence_alone(const Sequence& sequence, const Checker& check, int version) {
    if (sequence.empty())
        check.fail("sequence", "must list at least one pattern block");
    for (std::size_t i = 0; i < sequence.size(); ++i) {
        const PatternBlock& block = sequence[i];
        if (const auto* p = std::get_if<PhaseBlock>(&block)) {
            check_phase(*p, i, check);
        } else if (const auto* m = std::get_if<MicroPhaseBlock>(&block)) {
            check_micro_phase(*m, i, check);
        } else if (const auto* g = std::get_if<GrayBlock>(&block)) {
            check_gray(sequence, *g, i, check, version);
        } else if (const auto* c = std::get_if<CenterlineBlock>(&block)) {
            if (!std::isfinite(c->position)) {
                check.fail(block_field(i, "position"), "non-finite number");
            }
            if (!std::isfinite(c->width))
                check.fail(block_field(i, "width"), "non-finite number");
            if (!(c->width > 0.0)) {
                check.fail(block_field(i, "width"),
                           "must be > 0 projector pixels, got " + format_real(c->width));
            }
        }
    }
}

void check_sequence_on_projector(const Sequence& sequence, Size projector, const Checker& check,
                                 int version) {
    check_sequence_alone(sequence, check, version);
    for (std::size_t i = 0; i < sequence.size(); ++i) {
        if (const auto* g = std::get_if<GrayBlock>(&sequence[i])) {
            check_gray_coverage(*g, i, projector, check);
        } else if (const auto* m = std::get_if<MicroPhaseBlock>(&sequence[i])) {
            const int extent = m->axis == Axis::x ? projector.width : projector.height;
            for (std::size_t k = 0; k < m->periods.size(); ++k) {
                if (!(m->periods[k] < static_cast<double>(extent))) {
                    check.fail(item(block_field(i, "periods"), k),
                               "micro phase periods must be below the projector's " +
                                   std::to_string(extent) +
                                   (m->axis == Axis::x ? " columns" : " rows") + ", got " +
                                   format_real(m->periods[k]));
                }
            }
        } else if (const auto* c = std::get_if<CenterlineBlock>(&sequence[i])) {
            // Lit pixels: integers i in [0, extent - 1] with |i - position| <= width / 2.
            const int extent = c->axis == Axis::x ? projector.width : projector.height;
            const double first = std::max(0.0, std::ceil(c->position - 0.5 * c->width));
            const double last =
                std::min(static_cast<double>(extent - 1), std::floor(c->position + 0.5 * c->width));
            if (first > last) {
                check.fail(block_field(i, "position"),
                           "the line (position " + format_real(c->position) + ", width " +
                               format_real(c->width) + ") lights no pixel of the " +
                               std::to_string(extent) + " projector " +
                               (c->axis == Axis::x ? "columns" : "rows"));
            }
        }
    }
}

void check_size(const Size& size, const std::string& field, const Checker& check) {
    for (const auto& [value, key] :
         {std::pair{size.width, "width"}, std::pair{size.height, "height"}}) {
        if (value < 1 || value > kMaxImageSide) {
            check.fail(child(field, key), "must be between 1 and " + std::to_string(kMaxImageSide) +
                                              " pixels, got " + std::to_string(value));
        }
    }
}

void check_manifest(const CaptureManifest& m, const Checker& check, int version) {
    check_size(m.camera, "camera", check);
    check_size(m.projector, "projector", check);
    check_sequence_on_projector(m.sequence, m.projector, check, version);
    if (m.bit_depth != 0 && (m.bit_depth < 8 || m.bit_depth > 16)) {
        check.fail("bit_depth", "must be 9 to 16 (bits in use of 16-bit frames) or 8 (8-bit "
                                "frames), got " +
                                    std::to_string(m.bit_depth));
    }

    if (m.frames.empty())
        check.fail("frames", "must list at least one frame");
    std::map<std::string, std::size_t> first_use;
    for (std::size_t i = 0; i < m.frames.size(); ++i) {
        const std::string field = item("frames", i);
        check_relative_name(m.frames[i], field, check);
        const auto [it, fresh] = first_use.emplace(normal_name(m.frames[i]), i);
        if (!fresh) {
            check.fail(field, "'" + m.frames[i] + "' is listed twice (also frames[" +
                                  std::to_string(it->second) + "])");
        }
    }
    std::int64_t expected = 0;
    for (const auto& block : m.sequence)
        expected += frame_count(block);
    if (static_cast<std::int64_t>(m.frames.size()) != expected) {
        check.fail("frames", std::to_string(m.frames.size()) +
                                 " frames listed but the sequence's blocks add up to " +
                                 std::to_string(expected) + " frames");
    }

    if (m.truth) {
        if (m.truth->xyz.empty() && m.truth->projector.empty()) {
            check.fail("truth", "lists no file (give xyz, projector or both)");
        }
        for (const auto& [name, key] :
             {std::pair{m.truth->xyz, "xyz"}, std::pair{m.truth->projector, "projector"}}) {
            if (name.empty())
                continue;
            const std::string field = child("truth", key);
            check_relative_name(name, field, check);
            if (auto it = first_use.find(normal_name(name)); it != first_use.end()) {
                check.fail(field,
                           "'" + name + "' is also frames[" + std::to_string(it->second) + "]");
            }
        }
        if (!m.truth->xyz.empty() && normal_name(m.truth->xyz) == normal_name(m.truth->projector)) {
            check.fail("truth.projector", "same file as truth.xyz");
        }
    }
    check_metadata_text(m.metadata_yaml, check);
}

} // namespace fpp::capture_check
