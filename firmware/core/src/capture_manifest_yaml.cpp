// capture.yaml (fpp-capture/1 and /2), scan sequence files and board.yaml:
// strict parsing and exact emitting (firmware/core/formats/capture-set.md).

#include "capture_manifest_check.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <map>
#include <optional>
#include <string_view>

namespace fpp {

namespace {

namespace fs = std::filesystem;
using capture_check::Checker;
using yaml_fields::child;
using yaml_fields::format_real;
using yaml_fields::format_string;
using yaml_fields::item;
using yaml_fields::read_text_file;
using yaml_fields::Reader;

// Keys that only fpp-capture/2 knows, per pattern.
const std::initializer_list<std::string_view> kPhaseKeysV2 = {
    "pattern",    "axis",         "period",   "fringes",        "steps",
    "shift_sign", "phase_offset", "shifting", "carrier_period", "carrier_steps"};
const std::initializer_list<std::string_view> kGrayKeysV2 = {
    "pattern", "axis",   "period", "bits",   "complementary",  "inverse",
    "code",    "levels", "order",  "offset", "offset_periods", "wrap"};

// Version 0 = a sequence file (no format key): every v2 form is accepted.
class ManifestParser {
public:
    ManifestParser(const fs::path& origin, int version) : yaml_(origin), version_(version) {}

    const Reader& reader() const { return yaml_; }
    const std::map<std::string, int>& lines() const { return lines_; }
    void set_projector(Size projector) { projector_ = projector; }

    Axis axis(const YAML::Node& node, const std::string& field) const {
        const std::string text = yaml_.string_value(node, field);
        if (const auto a = value_of(kAxisNames, text))
            return *a;
        yaml_.fail(node, field, unknown_name_message(kAxisNames, "axis", text, " or "));
    }

    PatternBlock block(const YAML::Node& node, const std::string& field) {
        note(node, field);
        if (!node.IsMap()) {
            yaml_.fail(node, field, "must be a map such as {pattern: phase, axis: x, ...}");
        }
        const std::string pattern =
            yaml_.string_value(yaml_.require(node, field, "pattern"), child(field, "pattern"));
        if (pattern == "white" || pattern == "black") {
            yaml_.expect_map(node, field, {"pattern"});
            if (pattern == "white")
                return WhiteBlock{};
            return BlackBlock{};
        }
        if (pattern == "phase")
            return phase(node, field);
        if (pattern == "gray")
            return gray(node, field);
        if (pattern == "micro_phase") {
            refuse_in_v1(node["pattern"], child(field, "pattern"), "pattern micro_phase");
            return micro_phase(node, field);
        }
        if (pattern == "centerline") {
            yaml_.expect_map(node, field, {"pattern", "axis", "position", "width"});
            CenterlineBlock b;
            b.axis = axis(get(node, field, "axis"), child(field, "axis"));
            b.position = yaml_.real_value(get(node, field, "position"), child(field, "position"));
            b.width = yaml_.real_value(get(node, field, "width"), child(field, "width"));
            return b;
        }
        yaml_.fail(node[std::string("pattern")], child(field, "pattern"),
                   "unknown pattern '" + pattern + "' (white, black, phase, gray, centerline" +
                       (version_ == 1 ? std::string(")") : ", micro_phase)"));
    }

    Sequence sequence(const YAML::Node& node, const std::string& field) {
        note(node, field);
        yaml_.expect_list(node, field);
        Sequence s;
        for (std::size_t i = 0; i < node.size(); ++i)
            s.push_back(block(node[i], item(field, i)));
        return s;
    }

    Size size(const YAML::Node& node, const std::string& field) {
        note(node, field);
        yaml_.expect_map(node, field, {"width", "height"});
        Size s;
        s.width = yaml_.int_value(yaml_.require(node, field, "width"), child(field, "width"));
        s.height = yaml_.int_value(yaml_.require(node, field, "height"), child(field, "height"));
        return s;
    }

    CaptureManifest manifest(const YAML::Node& root) {
        yaml_.expect_map(root, "",
                         {"format", "camera", "projector", "frames", "sequence", "truth",
                          "metadata", "bit_depth"});
        CaptureManifest m;
        m.camera = size(yaml_.require(root, "", "camera"), "camera");
        m.projector = size(yaml_.require(root, "", "projector"), "projector");
        capture_check::check_size(m.projector, "projector", Checker(yaml_.origin(), &lines_));
        set_projector(m.projector);

        const YAML::Node frames = yaml_.require(root, "", "frames");
        note(frames, "frames");
        yaml_.expect_list(frames, "frames");
        for (std::size_t i = 0; i < frames.size(); ++i) {
            note(frames[i], item("frames", i));
            m.frames.push_back(yaml_.string_value(frames[i], item("frames", i)));
        }
        m.sequence = sequence(yaml_.require(root, "", "sequence"), "sequence");
        if (const YAML::Node depth = root["bit_depth"]; depth.IsDefined()) {
            note(depth, "bit_depth");
            refuse_in_v1(depth, "bit_depth", "bit_depth");
            m.bit_depth = yaml_.int_value(depth, "bit_depth");
            if (m.bit_depth < 8 || m.bit_depth > 16) {
                yaml_.fail(depth, "bit_depth",
                           "must be 9 to 16 (bits in use of 16-bit frames) or 8 (8-bit frames), "
                           "got " +
                               std::to_string(m.bit_depth));
            }
        }

        if (const YAML::Node truth = root["truth"]; truth.IsDefined()) {
            note(truth, "truth");
            yaml_.expect_map(truth, "truth", {"xyz", "projector"});
            TruthFiles files;
            if (const YAML::Node v = truth["xyz"]; v.IsDefined()) {
                note(v, "truth.xyz");
                files.xyz = yaml_.string_value(v, "truth.xyz");
            }
            if (const YAML::Node v = truth["projector"]; v.IsDefined()) {
                note(v, "truth.projector");
                files.projector = yaml_.string_value(v, "truth.projector");
            }
            m.truth = files;
        }
        if (const YAML::Node metadata = root["metadata"];
            metadata.IsDefined() && !metadata.IsNull()) {
            yaml_.expect_any_map(metadata, "metadata");
            if (metadata.size() > 0)
                m.metadata_yaml = YAML::Dump(metadata);
        }
        capture_check::check_manifest(m, Checker(yaml_.origin(), &lines_), version_);
        return m;
    }

private:
    YAML::Node get(const YAML::Node& node, const std::string& field, const char* key) {
        YAML::Node value = yaml_.require(node, field, key);
        note(value, child(field, key));
        return value;
    }
    YAML::Node optional(const YAML::Node& node, const std::string& field, const char* key) {
        YAML::Node value = node[key];
        if (value.IsDefined())
            note(value, child(field, key));
        return value;
    }

    void refuse_in_v1(const YAML::Node& node, const std::string& field, const std::string& what) {
        if (version_ == 1) {
            yaml_.fail(node, field,
                       what + " needs format: fpp-capture/2 (this file is fpp-capture/1)");
        }
    }

    // v1: only the keys of version 1, a v2 key is named with the version it needs.
    void expect_keys(const YAML::Node& node, const std::string& field,
                     std::initializer_list<std::string_view> v1,
                     std::initializer_list<std::string_view> v2) {
        if (version_ == 1) {
            for (auto it = node.begin(); it != node.end(); ++it) {
                const YAML::Node key = it->first;
                if (!key.IsScalar())
                    continue; // expect_map names it
                const std::string name = key.Scalar();
                const bool in_v1 = std::find(v1.begin(), v1.end(), name) != v1.end();
                const bool in_v2 = std::find(v2.begin(), v2.end(), name) != v2.end();
                if (!in_v1 && in_v2)
                    refuse_in_v1(key, child(field, name), "key '" + name + "'");
            }
            yaml_.expect_map(node, field, v1);
        } else {
            yaml_.expect_map(node, field, v2);
        }
    }

    // A number, or (v2) a ratio "a/b".
    double period_value(const YAML::Node& node, const std::string& field) {
        if (version_ == 1 && node.IsScalar() && node.Scalar().find('/') != std::string::npos) {
            refuse_in_v1(node, field, "a ratio period");
        }
        return yaml_.real_or_ratio_value(node, field);
    }

    int extent(Axis a) const { return a == Axis::x ? projector_->width : projector_->height; }

    PatternBlock phase(const YAML::Node& node, const std::string& field) {
        expect_keys(node, field,
                    {"pattern", "axis", "period", "steps", "shift_sign", "phase_offset"},
                    kPhaseKeysV2);
        PhaseBlock b;
        b.axis = axis(get(node, field, "axis"), child(field, "axis"));
        const YAML::Node fringes = optional(node, field, "fringes");
        if (fringes.IsDefined()) {
            if (node["period"].IsDefined()) {
                yaml_.fail(fringes, child(field, "fringes"), "give period or fringes, not both");
            }
            const double count = yaml_.real_or_ratio_value(fringes, child(field, "fringes"));
            if (!(count > 0.0)) {
                yaml_.fail(fringes, child(field, "fringes"),
                           "must be > 0 fringes across the axis, got " + format_real(count));
            }
            if (!projector_) {
                yaml_.fail(fringes, child(field, "fringes"),
                           "needs the projector size, which a sequence file lacks (give period)");
            }
            b.period = static_cast<double>(extent(b.axis)) / count;
        } else {
            if (!node["period"].IsDefined() && version_ != 1) {
                yaml_.fail(node, child(field, "period"), "missing field (give period or fringes)");
            }
            b.period = period_value(get(node, field, "period"), child(field, "period"));
        }
        if (auto v = optional(node, field, "shifting"); v.IsDefined()) {
            const std::string text = yaml_.string_value(v, child(field, "shifting"));
            if (const auto shifting = value_of(kPhaseShiftingNames, text)) {
                b.shifting = *shifting;
            } else {
                yaml_.fail(v, child(field, "shifting"),
                           unknown_name_message(kPhaseShiftingNames, "shifting", text));
            }
        }
        if (b.shifting == PhaseShifting::two_plus_one && !node["steps"].IsDefined()) {
            b.steps = 3;
        } else {
            b.steps = yaml_.int_value(get(node, field, "steps"), child(field, "steps"));
        }
        if (auto v = optional(node, field, "shift_sign"); v.IsDefined()) {
            b.shift_sign = yaml_.int_value(v, child(field, "shift_sign"));
        }
        if (auto v = optional(node, field, "phase_offset"); v.IsDefined()) {
            b.phase_offset = yaml_.real_value(v, child(field, "phase_offset"));
        }
        const YAML::Node carrier_period = optional(node, field, "carrier_period");
        const YAML::Node carrier_steps = optional(node, field, "carrier_steps");
        if (b.shifting == PhaseShifting::modulated) {
            b.carrier_period = yaml_.real_or_ratio_value(get(node, field, "carrier_period"),
                                                         child(field, "carrier_period"));
            b.carrier_steps =
                yaml_.int_value(get(node, field, "carrier_steps"), child(field, "carrier_steps"));
        } else {
            for (const auto& [value, key] : {std::pair{carrier_period, "carrier_period"},
                                             std::pair{carrier_steps, "carrier_steps"}}) {
                if (value.IsDefined()) {
                    yaml_.fail(value, child(field, key), "only with shifting: modulated");
                }
            }
        }
        return b;
    }

    PatternBlock micro_phase(const YAML::Node& node, const std::string& field) {
        yaml_.expect_map(
            node, field,
            {"pattern", "axis", "periods", "shift_sign", "phase_offset", "extra_phase_offsets"});
        MicroPhaseBlock b;
        b.axis = axis(get(node, field, "axis"), child(field, "axis"));
        const YAML::Node periods = get(node, field, "periods");
        const std::string list = child(field, "periods");
        yaml_.expect_list(periods, list);
        for (std::size_t k = 0; k < periods.size(); ++k) {
            note(periods[k], item(list, k));
            b.periods.push_back(yaml_.real_or_ratio_value(periods[k], item(list, k)));
        }
        if (auto v = optional(node, field, "shift_sign"); v.IsDefined()) {
            b.shift_sign = yaml_.int_value(v, child(field, "shift_sign"));
        }
        if (auto v = optional(node, field, "phase_offset"); v.IsDefined()) {
            b.phase_offset = yaml_.real_value(v, child(field, "phase_offset"));
        }
        if (auto v = optional(node, field, "extra_phase_offsets"); v.IsDefined()) {
            const std::string extra = child(field, "extra_phase_offsets");
            yaml_.expect_list(v, extra);
            for (std::size_t k = 0; k < v.size(); ++k) {
                b.extra_phase_offsets.push_back(yaml_.real_value(v[k], item(extra, k)));
            }
        }
        return b;
    }

    PatternBlock gray(const YAML::Node& node, const std::string& field) {
        expect_keys(node, field, {"pattern", "axis", "period", "bits", "complementary", "inverse"},
                    kGrayKeysV2);
        GrayBlock b;
        b.axis = axis(get(node, field, "axis"), child(field, "axis"));
        b.period = period_value(get(node, field, "period"), child(field, "period"));
        b.bits = yaml_.int_value(get(node, field, "bits"), child(field, "bits"));
        if (auto v = optional(node, field, "complementary"); v.IsDefined()) {
            b.complementary = yaml_.bool_value(v, child(field, "complementary"));
        }
        if (auto v = optional(node, field, "inverse"); v.IsDefined()) {
            b.inverse = yaml_.bool_value(v, child(field, "inverse"));
        }
        if (auto v = optional(node, field, "code"); v.IsDefined()) {
            const std::string text = yaml_.string_value(v, child(field, "code"));
            if (const auto code = value_of(kCodeKindNames, text)) {
                b.code = *code;
            } else {
                yaml_.fail(v, child(field, "code"),
                           unknown_name_message(kCodeKindNames, "code", text));
            }
        }
        if (auto v = optional(node, field, "levels"); v.IsDefined()) {
            b.levels = yaml_.int_value(v, child(field, "levels"));
        }
        if (auto v = optional(node, field, "order"); v.IsDefined()) {
            const std::string text = yaml_.string_value(v, child(field, "order"));
            if (const auto order = value_of(kDigitOrderNames, text)) {
                b.order = *order;
            } else {
                yaml_.fail(v, child(field, "order"),
                           unknown_name_message(kDigitOrderNames, "order", text));
            }
        }
        const YAML::Node offset = optional(node, field, "offset");
        const YAML::Node offset_periods = optional(node, field, "offset_periods");
        if (offset.IsDefined() && offset_periods.IsDefined()) {
            yaml_.fail(offset_periods, child(field, "offset_periods"),
                       "give offset or offset_periods, not both");
        }
        if (offset.IsDefined()) {
            b.offset = yaml_.real_or_ratio_value(offset, child(field, "offset"));
        } else if (offset_periods.IsDefined()) {
            b.offset = yaml_.real_or_ratio_value(offset_periods, child(field, "offset_periods")) *
                       b.period;
        }
        if (auto v = optional(node, field, "wrap"); v.IsDefined()) {
            b.wrap = yaml_.bool_value(v, child(field, "wrap"));
        }
        return b;
    }

    void note(const YAML::Node& node, const std::string& field) {
        if (node.IsDefined() && !node.Mark().is_null())
            lines_[field] = node.Mark().line + 1;
    }

    Reader yaml_;
    int version_;
    std::optional<Size> projector_;
    std::map<std::string, int> lines_;
};

// yaml-cpp throws its own exceptions for a few malformed inputs even after
// our type checks; report them as input errors of the file.
template <class F> auto with_yaml_errors(const fs::path& origin, F&& f) {
    try {
        return f();
    } catch (const YAML::Exception& e) {
        throw InputError(origin, "", std::string("cannot be read as YAML: ") + e.what());
    }
}

// 1 or 2 from the `format` field.
int format_version(const Reader& yaml, const YAML::Node& root) {
    if (!root.IsMap())
        yaml.fail(root, "", "must be a YAML map with format: fpp-capture/2");
    const std::string format = yaml.string_value(yaml.require(root, "", "format"), "format");
    if (format == kCaptureFormat)
        return 1;
    if (format == kCaptureFormatV2)
        return 2;
    yaml.fail(root["format"], "format",
              "unknown format '" + format + "' (this reader knows " + kCaptureFormat + " and " +
                  kCaptureFormatV2 + ")");
}

// ---------------------------------------------------------------------------
// YAML writing
// ---------------------------------------------------------------------------

std::string block_yaml(const PatternBlock& block, bool v2) {
    std::string s = "  - pattern: " + pattern_name(block) + "\n";
    auto line = [&s](const char* key, const std::string& value) {
        s += std::string("    ") + key + ": " + value + "\n";
    };
    if (const auto* p = std::get_if<PhaseBlock>(&block)) {
        line("axis", to_string(p->axis));
        line("period", format_real(p->period));
        line("steps", std::to_string(p->steps));
        line("shift_sign", std::to_string(p->shift_sign));
        line("phase_offset", format_real(p->phase_offset));
        if (v2)
            line("shifting", to_string(p->shifting));
        if (p->shifting == PhaseShifting::modulated) {
            line("carrier_period", format_real(p->carrier_period));
            line("carrier_steps", std::to_string(p->carrier_steps));
        }
    } else if (const auto* g = std::get_if<GrayBlock>(&block)) {
        line("axis", to_string(g->axis));
        line("period", format_real(g->period));
        line("bits", std::to_string(g->bits));
        line("complementary", g->complementary ? "true" : "false");
        line("inverse", g->inverse ? "true" : "false");
        if (v2) {
            line("code", name_of(kCodeKindNames, g->code, "binary"));
            line("levels", std::to_string(g->levels));
            line("order", name_of(kDigitOrderNames, g->order, "lsb_first"));
            line("offset", format_real(g->offset));
            if (g->wrap)
                line("wrap", "true");
        }
    } else if (const auto* m = std::get_if<MicroPhaseBlock>(&block)) {
        line("axis", to_string(m->axis));
        std::string list = "[";
        for (std::size_t k = 0; k < m->periods.size(); ++k) {
            list += (k ? ", " : "") + format_real(m->periods[k]);
        }
        line("periods", list + "]");
        line("shift_sign", std::to_string(m->shift_sign));
        line("phase_offset", format_real(m->phase_offset));
        if (!m->extra_phase_offsets.empty()) {
            std::string extra = "[";
            for (std::size_t k = 0; k < m->extra_phase_offsets.size(); ++k) {
                extra += (k ? ", " : "") + format_real(m->extra_phase_offsets[k]);
            }
            line("extra_phase_offsets", extra + "]");
        }
    } else if (const auto* c = std::get_if<CenterlineBlock>(&block)) {
        line("axis", to_string(c->axis));
        line("position", format_real(c->position));
        line("width", format_real(c->width));
    }
    return s;
}

std::string metadata_yaml(const std::string& text) {
    const YAML::Node node = YAML::Load(text); // validated before
    if (node.IsNull() || node.size() == 0)
        return "metadata: {}\n";
    YAML::Emitter emitter;
    emitter << node;
    const std::string dumped = emitter.c_str();
    if (!dumped.empty() && dumped[0] == '{')
        return "metadata: " + dumped + "\n";
    std::string out = "metadata:\n";
    std::size_t start = 0;
    while (start <= dumped.size()) {
        const std::size_t end = dumped.find('\n', start);
        const std::string line = dumped.substr(start, end == std::string::npos ? end : end - start);
        out += line.empty() ? "\n" : "  " + line + "\n";
        if (end == std::string::npos)
            break;
        start = end + 1;
    }
    return out;
}

} // namespace

CaptureManifest parse_manifest(const std::string& yaml_text, const std::filesystem::path& origin) {
    return with_yaml_errors(origin, [&] {
        const Reader yaml(origin);
        const YAML::Node root = yaml.load(yaml_text);
        ManifestParser parser(origin, format_version(yaml, root));
        return parser.manifest(root);
    });
}

CaptureManifest read_manifest(const std::filesystem::path& path) {
    return parse_manifest(read_text_file(path), path);
}

Sequence parse_sequence(const std::string& yaml_text, const std::filesystem::path& origin) {
    return with_yaml_errors(origin, [&] {
        ManifestParser parser(origin, 0);
        const YAML::Node root = parser.reader().load(yaml_text);
        if (!root.IsMap()) {
            parser.reader().fail(root, "", "must be a YAML map with a sequence: list");
        }
        Sequence s = parser.sequence(parser.reader().require(root, "", "sequence"), "sequence");
        capture_check::check_sequence_alone(s, Checker(origin, &parser.lines()), 2);
        return s;
    });
}

Sequence read_sequence(const std::filesystem::path& path) {
    return parse_sequence(read_text_file(path), path);
}

std::string manifest_to_yaml(const CaptureManifest& manifest) {
    validate_manifest(manifest, capture_check::kManifestName);
    const CaptureManifest& m = manifest;
    const bool v2 = capture_check::uses_version_2(m);
    std::string s;
    s += std::string("format: ") + (v2 ? kCaptureFormatV2 : kCaptureFormat) + "\n";
    s += "camera:    {width: " + std::to_string(m.camera.width) +
         ", height: " + std::to_string(m.camera.height) + "}\n";
    s += "projector: {width: " + std::to_string(m.projector.width) +
         ", height: " + std::to_string(m.projector.height) + "}\n";
    if (m.bit_depth != 0)
        s += "bit_depth: " + std::to_string(m.bit_depth) + "\n";

    // Flow list as in the spec, wrapped at about 100 columns.
    std::string line = "frames: [";
    const std::string indent(line.size(), ' ');
    for (std::size_t i = 0; i < m.frames.size(); ++i) {
        const std::string name = format_string(m.frames[i]) + (i + 1 < m.frames.size() ? "," : "]");
        if (line.size() > indent.size() && line.size() + 1 + name.size() > 100) {
            s += line + "\n";
            line = indent;
        } else if (i > 0) {
            line += " ";
        }
        line += name;
    }
    s += line + "\n";

    s += "sequence:\n";
    for (const auto& block : m.sequence)
        s += block_yaml(block, v2);
    if (m.truth) {
        s += "truth:\n";
        if (!m.truth->xyz.empty())
            s += "  xyz: " + format_string(m.truth->xyz) + "\n";
        if (!m.truth->projector.empty()) {
            s += "  projector: " + format_string(m.truth->projector) + "\n";
        }
    }
    s += metadata_yaml(m.metadata_yaml);
    return s;
}

BoardDescription parse_board(const std::string& yaml_text, const std::filesystem::path& origin) {
    return with_yaml_errors(origin, [&] {
        const Reader yaml(origin);
        const YAML::Node root = yaml.load(yaml_text);
        if (!root.IsMap())
            yaml.fail(root, "", "must be a YAML map with format: fpp-board/1");
        const std::string format = yaml.string_value(yaml.require(root, "", "format"), "format");
        if (format != kBoardFormat) {
            yaml.fail(root["format"], "format",
                      "unknown format '" + format + "' (this reader knows " + kBoardFormat + ")");
        }
        yaml.expect_map(root, "", {"format", "kind", "inner_corners", "square_size"});
        const YAML::Node kind_node = yaml.require(root, "", "kind");
        const std::string kind = yaml.string_value(kind_node, "kind");
        BoardDescription board;
        const YAML::Node corners = root["inner_corners"];
        const YAML::Node square = root["square_size"];
        if (kind == "checkerboard") {
            board.kind = BoardDescription::Kind::checkerboard;
            const YAML::Node list = yaml.require(root, "", "inner_corners");
            yaml.expect_list(list, "inner_corners");
            if (list.size() != 2) {
                yaml.fail(list, "inner_corners",
                          "must be [columns, rows], got " + std::to_string(list.size()) +
                              " values");
            }
            board.inner_columns = yaml.int_value(list[0], "inner_corners[0]");
            board.inner_rows = yaml.int_value(list[1], "inner_corners[1]");
            for (const auto& [value, field] : {std::pair{board.inner_columns, "inner_corners[0]"},
                                               std::pair{board.inner_rows, "inner_corners[1]"}}) {
                if (value < 2) {
                    yaml.fail(list, field,
                              "a checkerboard needs at least 2 inner corners per "
                              "direction, got " +
                                  std::to_string(value));
                }
            }
            yaml.require(root, "", "square_size");
        } else if (kind == "plane") {
            board.kind = BoardDescription::Kind::plane;
            if (corners.IsDefined()) {
                yaml.fail(corners, "inner_corners", "only for kind checkerboard");
            }
        } else {
            yaml.fail(kind_node, "kind",
                      "unknown board kind '" + kind + "' (checkerboard or plane)");
        }
        if (square.IsDefined()) {
            board.square_size = yaml.real_value(square, "square_size");
            if (!(board.square_size > 0.0)) {
                yaml.fail(square, "square_size",
                          "must be > 0 mm, got " + format_real(board.square_size));
            }
        }
        return board;
    });
}

BoardDescription read_board(const std::filesystem::path& path) {
    return parse_board(read_text_file(path), path);
}

} // namespace fpp
