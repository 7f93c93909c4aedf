#include "fpp/capture_set.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/parallel.hpp"
#include "fpp/yaml_fields.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <exception>
#include <functional>
#include <map>
#include <set>

namespace fpp {

namespace {

// "" for a regular file, else why not: "not found", or the file system's
// reason for a name it cannot look up (too long, a loop of links, ...),
// which must not escape as std::filesystem::filesystem_error.
std::string not_a_regular_file(const std::filesystem::path& path) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (std::filesystem::is_regular_file(status))
        return {};
    if (ec && ec != std::errc::no_such_file_or_directory)
        return "cannot be looked up: " + ec.message();
    return std::filesystem::exists(status) ? "is not a regular file" : "not found";
}

namespace fs = std::filesystem;
using yaml_fields::child;
using yaml_fields::format_real;
using yaml_fields::format_string;
using yaml_fields::item;
using yaml_fields::read_text_file;
using yaml_fields::Reader;

constexpr int kMaxImageSide = 65535; // PNG readers refuse larger frames too
constexpr int kMaxGrayBits = 30;     // floor(p/period) is coded in an int
constexpr const char* kManifestName = "capture.yaml";

// ---------------------------------------------------------------------------
// Validation of the parsed structures. Shared by the reader (which passes the
// YAML line of each field so that messages point into the file) and by the
// writer (which validates manifests built in code).
// ---------------------------------------------------------------------------

class Checker {
public:
    Checker(fs::path origin, const std::map<std::string, int>* lines)
        : origin_(std::move(origin)), lines_(lines) {}

    [[noreturn]] void fail(const std::string& field, const std::string& message) const {
        throw InputError(origin_, field, message + where(field));
    }

private:
    // " (line N)" of the field or of its nearest parent that has a line.
    std::string where(std::string field) const {
        if (!lines_) return {};
        while (!field.empty()) {
            if (auto it = lines_->find(field); it != lines_->end()) {
                return " (line " + std::to_string(it->second) + ")";
            }
            const auto cut = field.find_last_of(".[");
            if (cut == std::string::npos) break;
            field.erase(cut);
        }
        return {};
    }

    fs::path origin_;
    const std::map<std::string, int>* lines_;
};

std::string block_field(std::size_t index, const char* key) {
    return child(item("sequence", index), key);
}

void check_period(const Checker& check, std::size_t index, double period) {
    if (!std::isfinite(period)) check.fail(block_field(index, "period"), "non-finite number");
    if (!(period > 0.0)) {
        check.fail(block_field(index, "period"),
                   "must be > 0 projector pixels, got " + format_real(period));
    }
}

bool same_period(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(a, b); }

// Checks that need no projector size.
void check_sequence_alone(const Sequence& sequence, const Checker& check) {
    if (sequence.empty()) check.fail("sequence", "must list at least one pattern block");
    for (std::size_t i = 0; i < sequence.size(); ++i) {
        const PatternBlock& block = sequence[i];
        if (const auto* p = std::get_if<PhaseBlock>(&block)) {
            check_period(check, i, p->period);
            if (p->steps < 3) {
                check.fail(block_field(i, "steps"),
                           "must be at least 3 (N >= 3), got " + std::to_string(p->steps));
            }
            if (p->shift_sign != 1 && p->shift_sign != -1) {
                check.fail(block_field(i, "shift_sign"),
                           "must be 1 or -1, got " + std::to_string(p->shift_sign));
            }
            if (!std::isfinite(p->phase_offset)) {
                check.fail(block_field(i, "phase_offset"), "non-finite number");
            }
        } else if (const auto* g = std::get_if<GrayBlock>(&block)) {
            check_period(check, i, g->period);
            if (g->bits < 1 || g->bits > kMaxGrayBits) {
                check.fail(block_field(i, "bits"), "must be between 1 and " +
                                                       std::to_string(kMaxGrayBits) + ", got " +
                                                       std::to_string(g->bits));
            }
            // A Gray code numbers the periods of a phase block on the same axis.
            std::string periods;
            bool found = false;
            for (const PatternBlock& other : sequence) {
                const auto* q = std::get_if<PhaseBlock>(&other);
                if (!q || q->axis != g->axis) continue;
                periods += (periods.empty() ? "" : ", ") + format_real(q->period);
                found = found || same_period(q->period, g->period);
            }
            if (!found) {
                check.fail(block_field(i, "period"),
                           format_real(g->period) + " is not the period of any phase block on axis " +
                               to_string(g->axis) + " (the Gray code indexes a phase block's periods; " +
                               (periods.empty() ? std::string("there is no phase block on this axis")
                                                : "phase periods on this axis: " + periods) +
                               ")");
            }
        } else if (const auto* c = std::get_if<CenterlineBlock>(&block)) {
            if (!std::isfinite(c->position)) {
                check.fail(block_field(i, "position"), "non-finite number");
            }
            if (!std::isfinite(c->width)) check.fail(block_field(i, "width"), "non-finite number");
            if (!(c->width > 0.0)) {
                check.fail(block_field(i, "width"),
                           "must be > 0 projector pixels, got " + format_real(c->width));
            }
        }
    }
}

int extent_along(Axis axis, Size projector) {
    return axis == Axis::x ? projector.width : projector.height;
}

const char* extent_name(Axis axis) { return axis == Axis::x ? "columns" : "rows"; }

void check_sequence_on_projector(const Sequence& sequence, Size projector, const Checker& check) {
    check_sequence_alone(sequence, check);
    for (std::size_t i = 0; i < sequence.size(); ++i) {
        if (const auto* g = std::get_if<GrayBlock>(&sequence[i])) {
            const int extent = extent_along(g->axis, projector);
            const double last = std::floor(static_cast<double>(extent - 1) / g->period);
            if (last >= std::ldexp(1.0, g->bits)) {
                int needed = g->bits;
                while (needed < kMaxGrayBits && std::ldexp(1.0, needed) <= last) ++needed;
                check.fail(block_field(i, "bits"),
                           std::to_string(g->bits) + " bits number periods 0 to " +
                               std::to_string((std::int64_t{1} << g->bits) - 1) + ", but the " +
                               std::to_string(extent) + " projector " + extent_name(g->axis) +
                               " span periods 0 to " + format_real(last) + " at period " +
                               format_real(g->period) + ": at least " + std::to_string(needed) +
                               " bits are needed");
            }
        } else if (const auto* c = std::get_if<CenterlineBlock>(&sequence[i])) {
            // Lit pixels: integers i in [0, extent - 1] with |i - position| <= width / 2.
            const int extent = extent_along(c->axis, projector);
            const double first = std::max(0.0, std::ceil(c->position - 0.5 * c->width));
            const double last =
                std::min(static_cast<double>(extent - 1), std::floor(c->position + 0.5 * c->width));
            if (first > last) {
                check.fail(block_field(i, "position"),
                           "the line (position " + format_real(c->position) + ", width " +
                               format_real(c->width) + ") lights no pixel of the " +
                               std::to_string(extent) + " projector " + extent_name(c->axis));
            }
        }
    }
}

void check_size(const Size& size, const std::string& field, const Checker& check) {
    for (const auto& [value, key] : {std::pair{size.width, "width"}, std::pair{size.height, "height"}}) {
        if (value < 1 || value > kMaxImageSide) {
            check.fail(child(field, key), "must be between 1 and " + std::to_string(kMaxImageSide) +
                                              " pixels, got " + std::to_string(value));
        }
    }
}

// A path relative to the capture folder that stays inside it.
void check_relative_name(const std::string& name, const std::string& field, const Checker& check) {
    if (name.empty()) check.fail(field, "empty file name");
    const fs::path p(name);
    if (p.is_absolute()) check.fail(field, "'" + name + "' must be relative to the capture folder");
    for (const auto& part : p) {
        if (part == "..") check.fail(field, "'" + name + "' must stay inside the capture folder");
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

YAML::Node parse_metadata_text(const std::string& text, const Checker& check) {
    YAML::Node node;
    try {
        node = YAML::Load(text);
    } catch (const YAML::Exception& e) {
        check.fail("metadata", "not valid YAML: " + e.msg);
    }
    if (!node.IsNull() && !node.IsMap()) check.fail("metadata", "must be a map");
    return node;
}

void check_manifest(const CaptureManifest& m, const Checker& check) {
    check_size(m.camera, "camera", check);
    check_size(m.projector, "projector", check);
    check_sequence_on_projector(m.sequence, m.projector, check);

    if (m.frames.empty()) check.fail("frames", "must list at least one frame");
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
    for (const auto& block : m.sequence) expected += frame_count(block);
    if (static_cast<std::int64_t>(m.frames.size()) != expected) {
        check.fail("frames", std::to_string(m.frames.size()) + " frames listed but the sequence's " +
                                 "blocks add up to " + std::to_string(expected) + " frames");
    }

    if (m.truth) {
        if (m.truth->xyz.empty() && m.truth->projector.empty()) {
            check.fail("truth", "lists no file (give xyz, projector or both)");
        }
        for (const auto& [name, key] :
             {std::pair{m.truth->xyz, "xyz"}, std::pair{m.truth->projector, "projector"}}) {
            if (name.empty()) continue;
            const std::string field = child("truth", key);
            check_relative_name(name, field, check);
            if (auto it = first_use.find(normal_name(name)); it != first_use.end()) {
                check.fail(field, "'" + name + "' is also frames[" + std::to_string(it->second) + "]");
            }
        }
        if (!m.truth->xyz.empty() && normal_name(m.truth->xyz) == normal_name(m.truth->projector)) {
            check.fail("truth.projector", "same file as truth.xyz");
        }
    }
    parse_metadata_text(m.metadata_yaml, check);
}

// ---------------------------------------------------------------------------
// YAML reading
// ---------------------------------------------------------------------------

class ManifestParser {
public:
    explicit ManifestParser(const fs::path& origin) : yaml_(origin) {}

    const Reader& reader() const { return yaml_; }
    const std::map<std::string, int>& lines() const { return lines_; }

    Axis axis(const YAML::Node& node, const std::string& field) {
        const std::string text = yaml_.string_value(node, field);
        if (text == "x") return Axis::x;
        if (text == "y") return Axis::y;
        yaml_.fail(node, field, "unknown axis '" + text + "' (x or y)");
    }

    PatternBlock block(const YAML::Node& node, const std::string& field) {
        note(node, field);
        if (!node.IsMap()) {
            yaml_.fail(node, field, "must be a map such as {pattern: phase, axis: x, ...}");
        }
        const std::string pattern = yaml_.string_value(yaml_.require(node, field, "pattern"),
                                                       child(field, "pattern"));
        auto get = [&](const char* key) {
            YAML::Node value = yaml_.require(node, field, key);
            note(value, child(field, key));
            return value;
        };
        auto optional = [&](const char* key) {
            YAML::Node value = node[key];
            if (value.IsDefined()) note(value, child(field, key));
            return value;
        };
        if (pattern == "white" || pattern == "black") {
            yaml_.expect_map(node, field, {"pattern"});
            if (pattern == "white") return WhiteBlock{};
            return BlackBlock{};
        }
        if (pattern == "phase") {
            yaml_.expect_map(node, field,
                             {"pattern", "axis", "period", "steps", "shift_sign", "phase_offset"});
            PhaseBlock b;
            b.axis = axis(get("axis"), child(field, "axis"));
            b.period = yaml_.real_value(get("period"), child(field, "period"));
            b.steps = yaml_.int_value(get("steps"), child(field, "steps"));
            if (auto v = optional("shift_sign"); v.IsDefined()) {
                b.shift_sign = yaml_.int_value(v, child(field, "shift_sign"));
            }
            if (auto v = optional("phase_offset"); v.IsDefined()) {
                b.phase_offset = yaml_.real_value(v, child(field, "phase_offset"));
            }
            return b;
        }
        if (pattern == "gray") {
            yaml_.expect_map(node, field,
                             {"pattern", "axis", "period", "bits", "complementary", "inverse"});
            GrayBlock b;
            b.axis = axis(get("axis"), child(field, "axis"));
            b.period = yaml_.real_value(get("period"), child(field, "period"));
            b.bits = yaml_.int_value(get("bits"), child(field, "bits"));
            if (auto v = optional("complementary"); v.IsDefined()) {
                b.complementary = yaml_.bool_value(v, child(field, "complementary"));
            }
            if (auto v = optional("inverse"); v.IsDefined()) {
                b.inverse = yaml_.bool_value(v, child(field, "inverse"));
            }
            return b;
        }
        if (pattern == "centerline") {
            yaml_.expect_map(node, field, {"pattern", "axis", "position", "width"});
            CenterlineBlock b;
            b.axis = axis(get("axis"), child(field, "axis"));
            b.position = yaml_.real_value(get("position"), child(field, "position"));
            b.width = yaml_.real_value(get("width"), child(field, "width"));
            return b;
        }
        yaml_.fail(node[std::string("pattern")], child(field, "pattern"),
                   "unknown pattern '" + pattern + "' (white, black, phase, gray, centerline)");
    }

    Sequence sequence(const YAML::Node& node, const std::string& field) {
        note(node, field);
        yaml_.expect_list(node, field);
        Sequence s;
        for (std::size_t i = 0; i < node.size(); ++i) s.push_back(block(node[i], item(field, i)));
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
        if (!root.IsMap()) yaml_.fail(root, "", "must be a YAML map with format: fpp-capture/1");
        const std::string format = yaml_.string_value(yaml_.require(root, "", "format"), "format");
        if (format != kCaptureFormat) {
            yaml_.fail(root["format"], "format",
                       "unknown format '" + format + "' (this reader knows " + kCaptureFormat + ")");
        }
        yaml_.expect_map(root, "",
                         {"format", "camera", "projector", "frames", "sequence", "truth", "metadata"});
        CaptureManifest m;
        m.camera = size(yaml_.require(root, "", "camera"), "camera");
        m.projector = size(yaml_.require(root, "", "projector"), "projector");

        const YAML::Node frames = yaml_.require(root, "", "frames");
        note(frames, "frames");
        yaml_.expect_list(frames, "frames");
        for (std::size_t i = 0; i < frames.size(); ++i) {
            note(frames[i], item("frames", i));
            m.frames.push_back(yaml_.string_value(frames[i], item("frames", i)));
        }
        m.sequence = sequence(yaml_.require(root, "", "sequence"), "sequence");

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
        if (const YAML::Node metadata = root["metadata"]; metadata.IsDefined() && !metadata.IsNull()) {
            yaml_.expect_any_map(metadata, "metadata");
            if (metadata.size() > 0) m.metadata_yaml = YAML::Dump(metadata);
        }
        check_manifest(m, Checker(yaml_.origin(), &lines_));
        return m;
    }

private:
    void note(const YAML::Node& node, const std::string& field) {
        if (node.IsDefined() && !node.Mark().is_null()) lines_[field] = node.Mark().line + 1;
    }

    Reader yaml_;
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

// ---------------------------------------------------------------------------
// YAML writing
// ---------------------------------------------------------------------------

std::string block_yaml(const PatternBlock& block) {
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
    } else if (const auto* g = std::get_if<GrayBlock>(&block)) {
        line("axis", to_string(g->axis));
        line("period", format_real(g->period));
        line("bits", std::to_string(g->bits));
        line("complementary", g->complementary ? "true" : "false");
        line("inverse", g->inverse ? "true" : "false");
    } else if (const auto* c = std::get_if<CenterlineBlock>(&block)) {
        line("axis", to_string(c->axis));
        line("position", format_real(c->position));
        line("width", format_real(c->width));
    }
    return s;
}

std::string metadata_yaml(const std::string& text) {
    const YAML::Node node = YAML::Load(text); // validated before
    if (node.IsNull() || node.size() == 0) return "metadata: {}\n";
    YAML::Emitter emitter;
    emitter << node;
    const std::string dumped = emitter.c_str();
    if (!dumped.empty() && dumped[0] == '{') return "metadata: " + dumped + "\n";
    std::string out = "metadata:\n";
    std::size_t start = 0;
    while (start <= dumped.size()) {
        const std::size_t end = dumped.find('\n', start);
        const std::string line = dumped.substr(start, end == std::string::npos ? end : end - start);
        out += line.empty() ? "\n" : "  " + line + "\n";
        if (end == std::string::npos) break;
        start = end + 1;
    }
    return out;
}

// Runs f(0..n-1) on up to four threads (the work is file decoding and
// fsync, not arithmetic); rethrows the exception of the lowest failing index.
void for_each_file(std::size_t n, const std::function<void(std::size_t)>& f) {
    if (n == 0) return;
    const int count = static_cast<int>(n);
    ThreadPool pool(std::min({ThreadPool::resolve_threads(0), 4, count}));
    std::vector<std::exception_ptr> errors(n);
    std::atomic<bool> failed{false};
    pool.parallel_for(count, 1, [&](int begin, int end, int) {
        for (int k = begin; k < end && !failed; ++k) {
            const auto i = static_cast<std::size_t>(k);
            try {
                f(i);
            } catch (...) {
                errors[i] = std::current_exception();
                failed = true;
            }
        }
    });
    for (const auto& e : errors) {
        if (e) std::rethrow_exception(e);
    }
}

// Message of an InputError without its "file: field: " prefix, to re-raise
// it with the frame's field.
std::string bare_message(const InputError& e) {
    std::string what = e.what();
    std::string prefix = e.file().string() + ": ";
    if (!e.field().empty()) prefix += e.field() + ": ";
    return what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what;
}

} // namespace

// ---------------------------------------------------------------------------

void validate_manifest(const CaptureManifest& manifest, const std::filesystem::path& origin) {
    check_manifest(manifest, Checker(origin, nullptr));
}

void validate_sequence(const Sequence& sequence, Size projector,
                       const std::filesystem::path& origin) {
    const Checker check(origin, nullptr);
    check_size(projector, "projector", check);
    check_sequence_on_projector(sequence, projector, check);
}

CaptureManifest parse_manifest(const std::string& yaml_text, const std::filesystem::path& origin) {
    return with_yaml_errors(origin, [&] {
        ManifestParser parser(origin);
        const YAML::Node root = parser.reader().load(yaml_text);
        return parser.manifest(root);
    });
}

CaptureManifest read_manifest(const std::filesystem::path& path) {
    return parse_manifest(read_text_file(path), path);
}

Sequence parse_sequence(const std::string& yaml_text, const std::filesystem::path& origin) {
    return with_yaml_errors(origin, [&] {
        ManifestParser parser(origin);
        const YAML::Node root = parser.reader().load(yaml_text);
        if (!root.IsMap()) parser.reader().fail(root, "", "must be a YAML map with a sequence: list");
        Sequence s = parser.sequence(parser.reader().require(root, "", "sequence"), "sequence");
        check_sequence_alone(s, Checker(origin, &parser.lines()));
        return s;
    });
}

Sequence read_sequence(const std::filesystem::path& path) {
    return parse_sequence(read_text_file(path), path);
}

CaptureSet read_capture_set(const std::filesystem::path& folder) {
    return read_capture_set(folder, [](const PatternBlock&) { return true; });
}

CaptureSet read_capture_set(const std::filesystem::path& folder,
                            const std::function<bool(const PatternBlock&)>& keep) {
    CaptureSet set;
    set.folder = folder;
    set.manifest = read_manifest(folder / kManifestName);
    // The kept blocks and their frames; listed[i]: where frame i is listed
    // in capture.yaml (errors name that field).
    std::vector<std::size_t> listed;
    {
        CaptureManifest& all = set.manifest;
        Sequence sequence;
        std::vector<std::string> frames;
        std::size_t first = 0;
        for (const PatternBlock& block : all.sequence) {
            const std::size_t count = static_cast<std::size_t>(frame_count(block));
            if (keep(block)) {
                sequence.push_back(block);
                for (std::size_t k = first; k < first + count && k < all.frames.size(); ++k) {
                    frames.push_back(all.frames[k]);
                    listed.push_back(k);
                }
            }
            first += count;
        }
        all.sequence = std::move(sequence);
        all.frames = std::move(frames);
    }
    const CaptureManifest& m = set.manifest;
    const std::size_t n = m.frames.size();

    // Cheap checks on every file first so that a bad set fails before decoding.
    std::vector<PngInfo> infos(n);
    for (std::size_t i = 0; i < n; ++i) {
        const fs::path path = folder / m.frames[i];
        const std::string field = item("frames", listed[i]);
        if (const std::string why = not_a_regular_file(path); !why.empty()) {
            throw InputError(path, field, "frame file " + why + " (listed in " +
                                              (folder / kManifestName).string() + ")");
        }
        try {
            infos[i] = read_png_info(path);
        } catch (const InputError& e) {
            throw InputError(path, field, bare_message(e));
        }
        const PngInfo& info = infos[i];
        if (info.channels != 1 || info.palette || (info.bit_depth != 8 && info.bit_depth != 16)) {
            throw InputError(path, field, "must be an 8- or 16-bit single-channel grey PNG (it has " +
                                              std::to_string(info.channels) + " channel(s)" +
                                              (info.palette ? ", palette" : "") + ", " +
                                              std::to_string(info.bit_depth) + " bits)");
        }
        if (info.size != m.camera) {
            throw InputError(path, field,
                             "frame is " + std::to_string(info.size.width) + "x" +
                                 std::to_string(info.size.height) + " pixels but camera is " +
                                 std::to_string(m.camera.width) + "x" +
                                 std::to_string(m.camera.height) + " in capture.yaml");
        }
        if (info.bit_depth != infos[0].bit_depth) {
            throw InputError(path, field,
                             "frame is " + std::to_string(info.bit_depth) + "-bit but " +
                                 item("frames", listed[0]) + " is " +
                                 std::to_string(infos[0].bit_depth) +
                                 "-bit (all frames of a set share one bit depth)");
        }
    }
    if (m.truth) {
        for (const auto& [name, key] :
             {std::pair{m.truth->xyz, "xyz"}, std::pair{m.truth->projector, "projector"}}) {
            if (name.empty()) continue;
            const fs::path path = folder / name;
            if (const std::string why = not_a_regular_file(path); !why.empty()) {
                throw InputError(path, child("truth", key), "truth file " + why + " (listed in " +
                                                                (folder / kManifestName).string() +
                                                                ")");
            }
        }
    }

    set.frames.resize(n);
    for_each_file(n, [&](std::size_t i) {
        const fs::path path = folder / m.frames[i];
        try {
            set.frames[i] = read_png_gray(path);
        } catch (const InputError& e) {
            throw InputError(path, item("frames", listed[i]), bare_message(e));
        }
        // The file may have changed since its header was read.
        if (set.frames[i].size() != m.camera || set.frames[i].bit_depth != infos[0].bit_depth) {
            throw InputError(path, item("frames", listed[i]),
                             "frame changed while the set was read");
        }
    });
    return set;
}

std::string manifest_to_yaml(const CaptureManifest& manifest) {
    validate_manifest(manifest, kManifestName);
    const CaptureManifest& m = manifest;
    std::string s;
    s += std::string("format: ") + kCaptureFormat + "\n";
    s += "camera:    {width: " + std::to_string(m.camera.width) +
         ", height: " + std::to_string(m.camera.height) + "}\n";
    s += "projector: {width: " + std::to_string(m.projector.width) +
         ", height: " + std::to_string(m.projector.height) + "}\n";

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
    for (const auto& block : m.sequence) s += block_yaml(block);
    if (m.truth) {
        s += "truth:\n";
        if (!m.truth->xyz.empty()) s += "  xyz: " + format_string(m.truth->xyz) + "\n";
        if (!m.truth->projector.empty()) {
            s += "  projector: " + format_string(m.truth->projector) + "\n";
        }
    }
    s += metadata_yaml(m.metadata_yaml);
    return s;
}

void write_capture_set(const std::filesystem::path& folder, const CaptureManifest& manifest,
                       const std::vector<Frame>& frames) {
    write_capture_set(folder, manifest, frames, TruthImages{});
}

void write_capture_set(const std::filesystem::path& folder, const CaptureManifest& manifest,
                       const std::vector<Frame>& frames, const TruthImages& truth) {
    const fs::path origin = folder / kManifestName;
    const Checker check(origin, nullptr);
    check_manifest(manifest, check);
    const CaptureManifest& m = manifest;

    if (frames.size() != m.frames.size()) {
        check.fail("frames", std::to_string(frames.size()) + " frame images given for " +
                                 std::to_string(m.frames.size()) + " listed frames");
    }
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const Frame& f = frames[i];
        const fs::path path = folder / m.frames[i];
        const std::string field = item("frames", i);
        if (f.bit_depth != 8 && f.bit_depth != 16) {
            throw InputError(path, field, "bit depth " + std::to_string(f.bit_depth) +
                                              " (frames are 8- or 16-bit)");
        }
        const int channels = f.bit_depth == 8 ? f.u8.channels() : f.u16.channels();
        if (channels != 1) {
            throw InputError(path, field, std::to_string(channels) + " channels (frames are grey)");
        }
        if (f.size() != m.camera) {
            throw InputError(path, field, "frame is " + std::to_string(f.size().width) + "x" +
                                              std::to_string(f.size().height) +
                                              " pixels but camera is " +
                                              std::to_string(m.camera.width) + "x" +
                                              std::to_string(m.camera.height));
        }
        if (f.bit_depth != frames[0].bit_depth) {
            throw InputError(path, field, "frame is " + std::to_string(f.bit_depth) +
                                              "-bit but frames[0] is " +
                                              std::to_string(frames[0].bit_depth) + "-bit");
        }
    }
    struct TruthEntry {
        std::string name;
        const Image<float>* image;
        const char* field;
        int channels;
    };
    const std::vector<TruthEntry> truth_entries = {
        {m.truth ? m.truth->xyz : "", truth.xyz, "truth.xyz", 3},
        {m.truth ? m.truth->projector : "", truth.projector, "truth.projector", 2}};
    for (const auto& t : truth_entries) {
        if (t.name.empty() != (t.image == nullptr)) {
            check.fail(t.field, t.name.empty() ? "an image is given but the manifest lists no file"
                                               : "listed in the manifest but no image is given");
        }
        if (!t.image) continue;
        if (t.image->size() != m.camera || t.image->channels() != t.channels) {
            check.fail(t.field, "image must be " + std::to_string(t.channels) + "-channel at " +
                                    "camera size " + std::to_string(m.camera.width) + "x" +
                                    std::to_string(m.camera.height));
        }
    }
    const std::string yaml = manifest_to_yaml(m);

    write_folder_atomically(folder, [&](const fs::path& temp) {
        // Subfolders named by frame paths, fsynced once everything is in them.
        std::set<fs::path> subfolders;
        auto prepare = [&](const std::string& name) {
            const fs::path parent = fs::path(name).parent_path();
            if (parent.empty()) return;
            fs::create_directories(temp / parent);
            for (fs::path p = parent; !p.empty(); p = p.parent_path()) subfolders.insert(temp / p);
        };
        for (const auto& name : m.frames) prepare(name);
        for (const auto& t : truth_entries) {
            if (t.image) prepare(t.name);
        }
        for_each_file(frames.size(),
                      [&](std::size_t i) { write_png_synced(temp / m.frames[i], frames[i]); });
        for (const auto& t : truth_entries) {
            if (t.image) write_tiff_synced(temp / t.name, *t.image);
        }
        write_file_synced(temp / kManifestName, yaml);
        for (auto it = subfolders.rbegin(); it != subfolders.rend(); ++it) fsync_path(*it);
    });
}

BoardDescription parse_board(const std::string& yaml_text, const std::filesystem::path& origin) {
    return with_yaml_errors(origin, [&] {
        const Reader yaml(origin);
        const YAML::Node root = yaml.load(yaml_text);
        if (!root.IsMap()) yaml.fail(root, "", "must be a YAML map with format: fpp-board/1");
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
                yaml.fail(list, "inner_corners", "must be [columns, rows], got " +
                                                     std::to_string(list.size()) + " values");
            }
            board.inner_columns = yaml.int_value(list[0], "inner_corners[0]");
            board.inner_rows = yaml.int_value(list[1], "inner_corners[1]");
            for (const auto& [value, field] : {std::pair{board.inner_columns, "inner_corners[0]"},
                                               std::pair{board.inner_rows, "inner_corners[1]"}}) {
                if (value < 2) {
                    yaml.fail(list, field, "a checkerboard needs at least 2 inner corners per "
                                           "direction, got " + std::to_string(value));
                }
            }
            yaml.require(root, "", "square_size");
        } else if (kind == "plane") {
            board.kind = BoardDescription::Kind::plane;
            if (corners.IsDefined()) {
                yaml.fail(corners, "inner_corners", "only for kind checkerboard");
            }
        } else {
            yaml.fail(kind_node, "kind", "unknown board kind '" + kind + "' (checkerboard or plane)");
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
