#pragma once
// Strict field readers over yaml-cpp for our file formats (capture sets,
// sequences, boards, simulator rigs and scenes): every failure is an
// InputError naming the file and the YAML path of the field ("camera.width",
// "frames[3]"), with its line where known. Also the scalar spellings our
// writers use, so that what we write reads back through these readers.

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>

namespace fpp::yaml_fields {

// "camera" + "width" -> "camera.width"; "" + "format" -> "format".
std::string child(const std::string& parent, std::string_view key);
// "frames", 3 -> "frames[3]".
std::string item(const std::string& parent, std::size_t index);

// The whole file as text; an InputError naming `path` if it cannot be read.
std::string read_text_file(const std::filesystem::path& path);

class Reader {
public:
    explicit Reader(std::filesystem::path origin) : origin_(std::move(origin)) {}

    const std::filesystem::path& origin() const { return origin_; }

    // Parses a whole document (a syntax error names the line and column).
    YAML::Node load(const std::string& text) const;
    // Reads and parses the file `origin()`.
    YAML::Node load_file() const;

    // Throws InputError(origin, field, message), with the node's line if it has one.
    [[noreturn]] void fail(const YAML::Node& node, const std::string& field,
                           const std::string& message) const;
    // For a value that is wrong as a whole rather than at one node.
    [[noreturn]] void fail(const std::string& field, const std::string& message) const;

    // The node must be a map whose keys are plain scalars from `allowed`,
    // each at most once.
    void expect_map(const YAML::Node& node, const std::string& field,
                    std::initializer_list<std::string_view> allowed) const;
    // A map without key restrictions (duplicates still rejected).
    void expect_any_map(const YAML::Node& node, const std::string& field) const;
    void expect_list(const YAML::Node& node, const std::string& field) const;
    // A list of exactly `size` entries.
    void expect_list(const YAML::Node& node, const std::string& field, std::size_t size) const;

    // map[key]; fails with "missing field" when absent.
    YAML::Node require(const YAML::Node& map, const std::string& parent,
                       std::string_view key) const;

    std::string string_value(const YAML::Node& node, const std::string& field) const;
    int int_value(const YAML::Node& node, const std::string& field) const;
    double real_value(const YAML::Node& node, const std::string& field) const;
    bool bool_value(const YAML::Node& node, const std::string& field) const;
    // A number, or a ratio of two numbers written `1920/58` (no spaces): the
    // double quotient of the two, as C++ divides them.
    double real_or_ratio_value(const YAML::Node& node, const std::string& field) const;

    // map[key] read as a real, or `fallback` when the key is absent.
    double real_value_or(const YAML::Node& map, const std::string& parent, std::string_view key,
                         double fallback) const;
    // A list of exactly N reals (a point, a size, a matrix row).
    template <std::size_t N>
    std::array<double, N> real_array(const YAML::Node& node, const std::string& field) const {
        expect_list(node, field, N);
        std::array<double, N> values{};
        for (std::size_t i = 0; i < N; ++i)
            values[i] = real_value(node[i], item(field, i));
        return values;
    }

private:
    // The scalar text of a plain (unquoted) scalar; `kind` names what was expected.
    std::string plain_scalar(const YAML::Node& node, const std::string& field,
                             const char* kind) const;
    void check_keys(const YAML::Node& node, const std::string& field,
                    std::initializer_list<std::string_view>* allowed) const;

    std::filesystem::path origin_;
};

// Shortest text that reads back to the same double; whole numbers get ".0"
// so that they read as reals ("2" -> "2.0").
std::string format_real(double value);
// `text` as a YAML scalar that reads back as the same string: plain where
// that is unambiguous, otherwise double-quoted with escapes.
std::string format_string(const std::string& text);

} // namespace fpp::yaml_fields
