#include "file_storage_yaml.hpp"

#include "fpp/error.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <string_view>
#include <vector>

namespace fpp::calib::detail {

namespace {

namespace fs = std::filesystem;

constexpr int max_depth = 16;
constexpr std::size_t wrap_column = 72;
constexpr int indent_step = 3; // OpenCV's own

bool is_name(const std::string& key) {
    if (key.empty() || !(std::isalpha(static_cast<unsigned char>(key[0])) || key[0] == '_'))
        return false;
    return std::all_of(key.begin(), key.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
    });
}

// The two tags OpenCV gives its matrices; yaml-cpp spells `!!x` in full.
const char* opencv_tag(const YAML::Node& node) {
    const std::string& tag = node.Tag();
    if (tag == "tag:yaml.org,2002:opencv-matrix")
        return "!!opencv-matrix";
    if (tag == "tag:yaml.org,2002:opencv-nd-matrix")
        return "!!opencv-nd-matrix";
    return nullptr;
}

// A line of YAML that is not blank, a comment or a directive.
bool is_content(std::string_view line) {
    const std::size_t first = line.find_first_not_of(" \t\r");
    return first != std::string_view::npos && line[first] != '#' && line[first] != '%';
}

bool has_content(std::string_view text) {
    for (std::size_t start = 0; start < text.size();) {
        const std::size_t end = std::min(text.find('\n', start), text.size());
        if (is_content(text.substr(start, end - start)) && !text.substr(start).starts_with("---") &&
            !text.substr(start).starts_with("..."))
            return true;
        start = end + 1;
    }
    return false;
}

// A second document begins after a line of content with a marker (`---`,
// `...`) or a directive. Checked on the text because yaml-cpp 0.7's LoadAll
// never returns from some malformed text (found by tests/fuzz: a first line
// that starts with ','); OpenCV writes one document.
void refuse_several_documents(std::string_view text, const fs::path& origin) {
    bool seen_content = false;
    int line = 1;
    for (std::size_t start = 0; start < text.size(); ++line) {
        const std::size_t end = std::min(text.find('\n', start), text.size());
        const std::string_view here = text.substr(start, end - start);
        const bool marker = here.starts_with("---") || here.starts_with("...");
        if (seen_content && (marker || here.starts_with("%")))
            throw InputError(origin, "line " + std::to_string(line),
                             "a second YAML document begins; a calibration file is one");
        seen_content = seen_content || (!marker && is_content(here));
        start = end + 1;
    }
}

class Writer {
public:
    Writer(const fs::path& origin, std::size_t max_output)
        : origin_(origin), max_output_(max_output) {}

    void block_map(const YAML::Node& map, int indent, int depth) {
        for (const auto& entry : map) {
            const std::string key = scalar_key(entry.first);
            const YAML::Node& value = entry.second;
            put(std::string(std::size_t(indent), ' ') + key + ":");
            const char* tag = opencv_tag(value);
            if (value.IsMap() && value.size() > 0) {
                if (tag != nullptr)
                    put(std::string(" ") + tag);
                newline();
                block_map(value, indent + indent_step, deeper(depth, key));
            } else {
                put(" ");
                flow(value, indent + indent_step, deeper(depth, key));
                newline();
            }
        }
    }

    std::string take() { return std::move(out_); }

private:
    int deeper(int depth, const std::string& key) const {
        if (depth + 1 > max_depth)
            throw InputError(origin_, key,
                             "nested more than " + std::to_string(max_depth) +
                                 " levels deep; a calibration file is not");
        return depth + 1;
    }

    std::string scalar_key(const YAML::Node& key) const {
        if (!key.IsScalar())
            throw InputError(origin_, "line " + std::to_string(key.Mark().line + 1),
                             "a key that is a list or a map");
        const std::string& name = key.Scalar();
        if (!is_name(name))
            throw InputError(origin_, "line " + std::to_string(key.Mark().line + 1),
                             "key '" + name.substr(0, 40) +
                                 "' is not a name (a letter or '_', then letters, digits, '_' "
                                 "or '-')");
        return name;
    }

    // Lists, maps inside lists and scalars, on one line wrapped at commas.
    void flow(const YAML::Node& node, int continuation, int depth) {
        if (node.IsSequence() || node.IsMap()) {
            const bool map = node.IsMap();
            if (const char* tag = opencv_tag(node); tag != nullptr && map)
                put(std::string(tag) + " ");
            put(map ? "{" : "[");
            bool first = true;
            for (const auto& item : node) {
                put(first ? " " : ", ");
                if (!first && column_ > wrap_column) {
                    newline();
                    put(std::string(std::size_t(continuation), ' '));
                }
                first = false;
                if (map) {
                    const std::string key = scalar_key(item.first);
                    put(key + ": ");
                    flow(item.second, continuation + indent_step, deeper(depth, key));
                } else {
                    flow(item, continuation + indent_step, deeper(depth, "a list"));
                }
            }
            put(first ? (map ? "}" : "]") : (map ? " }" : " ]"));
            return;
        }
        scalar(node);
    }

    // Plain when yaml-cpp read it plain and it is made of the characters of a
    // number or a name; otherwise double-quoted. An empty value is "".
    void scalar(const YAML::Node& node) {
        const std::string text = node.IsScalar() ? node.Scalar() : std::string();
        const bool plain_chars = !text.empty() && std::any_of(text.begin(), text.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c));
        }) && std::all_of(text.begin(), text.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '+' ||
                   c == '-' || c == '_';
        });
        if (node.IsScalar() && node.Tag() == "?" && plain_chars) {
            put(text);
            return;
        }
        std::string quoted = "\"";
        for (const char c : text) {
            const auto byte = static_cast<unsigned char>(c);
            if (byte < 0x20 || byte == 0x7f)
                throw InputError(origin_, "line " + std::to_string(node.Mark().line + 1),
                                 "a control character in a string");
            if (c == '"' || c == '\\')
                quoted += '\\';
            quoted += c;
        }
        put(quoted + "\"");
    }

    void put(const std::string& s) {
        out_ += s;
        column_ += s.size();
        if (out_.size() > max_output_)
            throw InputError(origin_, "",
                             "written as OpenCV writes YAML it grows past " +
                                 std::to_string(max_output_) +
                                 " bytes (four times the file and 4 KB): its aliases repeat "
                                 "too much");
    }
    void newline() {
        out_ += '\n';
        column_ = 0;
    }

    const fs::path& origin_;
    std::size_t max_output_;
    std::string out_;
    std::size_t column_ = 0;
};

} // namespace

std::string rewrite_yaml_for_opencv(const std::string& text, const fs::path& origin) {
    // OpenCV writes `%YAML:1.0`, which is not YAML's spelling of the
    // directive; the line is kept empty so that line numbers stay true.
    std::string yaml = text.substr(0, text.find('\0')); // what OpenCV would read
    if (yaml.starts_with("%YAML:"))
        yaml.erase(0, std::min(yaml.find('\n'), yaml.size()));
    refuse_several_documents(yaml, origin);
    YAML::Node root;
    try {
        root = YAML::Load(yaml);
    } catch (const YAML::Exception& e) {
        throw InputError(origin, "line " + std::to_string(e.mark.line + 1),
                         "not YAML, XML or JSON: " + e.msg);
    }
    if (root.IsNull())
        throw InputError(origin, "",
                         has_content(yaml) ? "not YAML, XML or JSON: no document where it starts"
                                           : "the file is empty");
    if (!root.IsMap())
        throw InputError(origin, "",
                         std::string("its top level is ") +
                             (root.IsSequence() ? "a list" : "a single value") +
                             ", not a map of keys");
    // Written again, a file is about as long as it was (OpenCV's files alike;
    // `{a,b}` can at most quadruple); aliases can make a few bytes stand for
    // gigabytes, and OpenCV's tree of them would fill the memory.
    Writer writer(origin, 4096 + 4 * yaml.size());
    writer.block_map(root, 0, 0);
    return "%YAML:1.0\n---\n" + writer.take();
}

} // namespace fpp::calib::detail
