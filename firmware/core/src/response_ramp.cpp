// The projector response ramp on disk (firmware/core/formats/response-ramp.md):
// a folder with ramp.yaml (fpp-response-ramp/1) and one grey PNG per level.

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/projector_response.hpp"
#include "fpp/yaml_fields.hpp"

#include <cstdio>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace fpp {

namespace {

namespace fs = std::filesystem;
using yaml_fields::format_string;
using yaml_fields::item;
using yaml_fields::read_text_file;
using yaml_fields::Reader;

constexpr const char* kRampManifest = "ramp.yaml";
constexpr int kMinLevels = 3; // 0, 255 and at least one level between to see a shape

// A problem with the levels: the message and the index it is at (npos: the
// list as a whole).
struct LevelsProblem {
    std::string message;
    std::size_t index = std::string::npos;
};

std::optional<LevelsProblem> levels_problem(const std::vector<int>& levels) {
    if (levels.size() < std::size_t(kMinLevels)) {
        return LevelsProblem{"needs at least " + std::to_string(kMinLevels) +
                             " levels (0, 255 and levels between), got " +
                             std::to_string(levels.size())};
    }
    for (std::size_t i = 0; i < levels.size(); ++i) {
        if (levels[i] < 0 || levels[i] > 255) {
            return LevelsProblem{"drive level " + std::to_string(levels[i]) +
                                     " is outside 0..255 (8-bit projector input)",
                                 i};
        }
        if (i > 0 && levels[i] <= levels[i - 1]) {
            return LevelsProblem{
                "levels must be strictly increasing: " + std::to_string(levels[i]) + " follows " +
                    std::to_string(levels[i - 1]),
                i};
        }
    }
    if (levels.front() != 0) {
        return LevelsProblem{"the first level must be 0 (projector off: the black level the "
                             "response is measured from), got " +
                                 std::to_string(levels.front()),
                             0};
    }
    if (levels.back() != 255) {
        return LevelsProblem{"the last level must be 255 (projector full on: the light the "
                             "response is scaled to), got " +
                                 std::to_string(levels.back()),
                             levels.size() - 1};
    }
    return std::nullopt;
}

std::string size_text(Size s) {
    return std::to_string(s.width) + "x" + std::to_string(s.height);
}

std::string frame_name(int level) {
    char name[32];
    std::snprintf(name, sizeof name, "level-%03d.png", level);
    return name;
}

// "" for a regular file, else why not (never a filesystem_error).
std::string not_a_regular_file(const fs::path& path) {
    std::error_code ec;
    const auto status = fs::status(path, ec);
    if (fs::is_regular_file(status))
        return {};
    if (ec && ec != std::errc::no_such_file_or_directory)
        return "cannot be looked up: " + ec.message();
    return fs::exists(status) ? "is not a regular file" : "not found";
}

// Message of an InputError without its "file: field: " prefix.
std::string bare_message(const InputError& e) {
    const std::string what = e.what();
    std::string prefix = e.file().string() + ": ";
    if (!e.field().empty())
        prefix += e.field() + ": ";
    return what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what;
}

std::string metadata_block(const std::string& metadata_yaml, const fs::path& origin) {
    if (metadata_yaml.empty())
        return {};
    YAML::Node node;
    try {
        node = YAML::Load(metadata_yaml);
    } catch (const YAML::Exception& e) {
        throw InputError(origin, "metadata", std::string("not valid YAML: ") + e.what());
    }
    if (node.IsNull())
        return {};
    if (!node.IsMap())
        throw InputError(origin, "metadata", "must be a YAML map");
    YAML::Emitter out;
    out << YAML::BeginMap << YAML::Key << "metadata" << YAML::Value << node << YAML::EndMap;
    return std::string(out.c_str()) + "\n";
}

std::string ramp_yaml(const ResponseRamp& ramp, const std::vector<std::string>& names,
                      const fs::path& origin) {
    std::string s = std::string("format: ") + kResponseRampFormat + "\n";
    s += "levels: [";
    for (std::size_t i = 0; i < ramp.levels.size(); ++i)
        s += (i ? ", " : "") + std::to_string(ramp.levels[i]);
    s += "]\nframes:\n";
    for (const std::string& name : names)
        s += "  - " + format_string(name) + "\n";
    return s + metadata_block(ramp.metadata_yaml, origin);
}

class RampParser {
public:
    explicit RampParser(fs::path origin) : yaml_(std::move(origin)) {}

    ResponseRamp parse(const std::string& text, std::vector<std::string>& names) const {
        const YAML::Node root = yaml_.load(text);
        if (!root.IsMap()) {
            yaml_.fail(root, "",
                       std::string("must be a YAML map with format: ") + kResponseRampFormat);
        }
        const YAML::Node format_node = yaml_.require(root, "", "format");
        const std::string format = yaml_.string_value(format_node, "format");
        if (format != kResponseRampFormat) {
            yaml_.fail(format_node, "format",
                       "unknown format '" + format + "' (this reader knows " + kResponseRampFormat +
                           ")");
        }
        yaml_.expect_map(root, "", {"format", "levels", "frames", "metadata"});
        ResponseRamp ramp;
        const YAML::Node levels = yaml_.require(root, "", "levels");
        yaml_.expect_list(levels, "levels");
        for (std::size_t i = 0; i < levels.size(); ++i)
            ramp.levels.push_back(yaml_.int_value(levels[i], item("levels", i)));
        if (const auto problem = levels_problem(ramp.levels)) {
            if (problem->index == std::string::npos)
                yaml_.fail(levels, "levels", problem->message);
            yaml_.fail(levels[problem->index], item("levels", problem->index), problem->message);
        }
        const YAML::Node frames = yaml_.require(root, "", "frames");
        yaml_.expect_list(frames, "frames");
        std::set<std::string> seen;
        for (std::size_t i = 0; i < frames.size(); ++i) {
            const std::string field = item("frames", i);
            const std::string name = yaml_.string_value(frames[i], field);
            const fs::path p(name);
            if (name.empty())
                yaml_.fail(frames[i], field, "empty file name");
            if (p.is_absolute())
                yaml_.fail(frames[i], field, "'" + name + "' must be relative to the ramp folder");
            for (const auto& part : p) {
                if (part == "..")
                    yaml_.fail(frames[i], field, "'" + name + "' must stay inside the ramp folder");
            }
            if (!seen.insert(p.lexically_normal().string()).second)
                yaml_.fail(frames[i], field, "'" + name + "' is listed twice");
            names.push_back(name);
        }
        if (frames.size() != ramp.levels.size()) {
            yaml_.fail(frames, "frames",
                       std::to_string(frames.size()) + " frames listed for " +
                           std::to_string(ramp.levels.size()) + " levels (one frame per level)");
        }
        if (const YAML::Node metadata = root["metadata"];
            metadata.IsDefined() && !metadata.IsNull()) {
            yaml_.expect_any_map(metadata, "metadata");
            if (metadata.size() > 0)
                ramp.metadata_yaml = YAML::Dump(metadata);
        }
        return ramp;
    }

private:
    Reader yaml_;
};

} // namespace

std::vector<int> standard_ramp_levels() {
    std::vector<int> levels;
    for (int level = 0; level < 255; level += 16)
        levels.push_back(level);
    levels.push_back(255);
    return levels;
}

Image<std::uint8_t> ramp_pattern(int level, Size projector) {
    if (level < 0 || level > 255)
        throw std::invalid_argument("ramp_pattern: level " + std::to_string(level) +
                                    " is outside 0..255");
    if (projector.width <= 0 || projector.height <= 0)
        throw std::invalid_argument("ramp_pattern: projector size must be positive");
    return Image<std::uint8_t>(projector, 1, static_cast<std::uint8_t>(level));
}

void validate_response_ramp(const ResponseRamp& ramp, const std::filesystem::path& origin) {
    if (const auto problem = levels_problem(ramp.levels)) {
        throw InputError(origin,
                         problem->index == std::string::npos ? std::string("levels")
                                                             : item("levels", problem->index),
                         problem->message);
    }
    if (ramp.frames.size() != ramp.levels.size()) {
        throw InputError(origin, "frames",
                         std::to_string(ramp.frames.size()) + " frames for " +
                             std::to_string(ramp.levels.size()) + " levels (one frame per level)");
    }
    for (std::size_t i = 0; i < ramp.frames.size(); ++i) {
        const Frame& f = ramp.frames[i];
        const std::string field = item("frames", i);
        if (f.bit_depth != 8 && f.bit_depth != 16) {
            throw InputError(origin, field,
                             "bit depth " + std::to_string(f.bit_depth) +
                                 " (frames are 8- or 16-bit)");
        }
        const int channels = f.bit_depth == 8 ? f.u8.channels() : f.u16.channels();
        if (channels != 1 || f.size().area() == 0) {
            throw InputError(origin, field, "must be a non-empty single-channel frame");
        }
        if (i > 0 && f.size() != ramp.frames[0].size()) {
            throw InputError(origin, field,
                             "frame is " + size_text(f.size()) + " pixels but frames[0] is " +
                                 size_text(ramp.frames[0].size()));
        }
        if (i > 0 && f.bit_depth != ramp.frames[0].bit_depth) {
            throw InputError(origin, field,
                             "frame is " + std::to_string(f.bit_depth) + "-bit but frames[0] is " +
                                 std::to_string(ramp.frames[0].bit_depth) +
                                 "-bit (all frames of a ramp share one bit depth)");
        }
    }
}

void write_response_ramp(const std::filesystem::path& folder, const ResponseRamp& ramp) {
    const fs::path origin = folder / kRampManifest;
    validate_response_ramp(ramp, origin);
    std::vector<std::string> names;
    for (const int level : ramp.levels)
        names.push_back(frame_name(level));
    const std::string yaml = ramp_yaml(ramp, names, origin);
    write_folder_atomically(folder, [&](const fs::path& temp) {
        for (std::size_t i = 0; i < names.size(); ++i)
            write_png_synced(temp / names[i], ramp.frames[i]);
        write_file_synced(temp / kRampManifest, yaml);
    });
}

ResponseRamp read_response_ramp(const std::filesystem::path& folder) {
    const fs::path origin = folder / kRampManifest;
    std::error_code ec;
    if (!fs::is_directory(folder, ec))
        throw InputError(folder, "", "not a folder (a response ramp is a folder with ramp.yaml)");
    std::vector<std::string> names;
    ResponseRamp ramp;
    try {
        ramp = RampParser(origin).parse(read_text_file(origin), names);
    } catch (const YAML::Exception& e) {
        throw InputError(origin, "", std::string("cannot be read as YAML: ") + e.what());
    }
    ramp.folder = folder;

    // Headers first: a wrong frame is named before any pixel is decoded.
    PngInfo first;
    for (std::size_t i = 0; i < names.size(); ++i) {
        const fs::path path = folder / names[i];
        const std::string field = item("frames", i);
        if (const std::string why = not_a_regular_file(path); !why.empty())
            throw InputError(path, field,
                             "frame file " + why + " (listed in " + origin.string() + ")");
        PngInfo info;
        try {
            info = read_png_info(path);
        } catch (const InputError& e) {
            throw InputError(path, field, bare_message(e));
        }
        if (info.channels != 1 || info.palette || (info.bit_depth != 8 && info.bit_depth != 16)) {
            throw InputError(path, field,
                             "must be an 8- or 16-bit single-channel grey PNG (it has " +
                                 std::to_string(info.channels) + " channel(s)" +
                                 (info.palette ? ", palette" : "") + ", " +
                                 std::to_string(info.bit_depth) + " bits)");
        }
        if (i == 0) {
            first = info;
        } else if (info.size != first.size) {
            throw InputError(path, field,
                             "frame is " + size_text(info.size) + " pixels but frames[0] is " +
                                 size_text(first.size));
        } else if (info.bit_depth != first.bit_depth) {
            throw InputError(path, field,
                             "frame is " + std::to_string(info.bit_depth) +
                                 "-bit but frames[0] is " + std::to_string(first.bit_depth) +
                                 "-bit (all frames of a ramp share one bit depth)");
        }
    }
    for (std::size_t i = 0; i < names.size(); ++i) {
        const fs::path path = folder / names[i];
        try {
            ramp.frames.push_back(read_png_gray(path));
        } catch (const InputError& e) {
            throw InputError(path, item("frames", i), bare_message(e));
        }
        if (ramp.frames.back().size() != first.size ||
            ramp.frames.back().bit_depth != first.bit_depth) {
            throw InputError(path, item("frames", i), "frame changed while the ramp was read");
        }
    }
    return ramp;
}

} // namespace fpp
