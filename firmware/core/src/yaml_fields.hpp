#pragma once
// Strict field readers over yaml-cpp for our file formats: every failure is an
// InputError naming the file and the YAML path of the field, with its line.
// Internal to fpp_core.

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

namespace fpp::yaml_fields {

// "camera" + "width" -> "camera.width"; "" + "format" -> "format".
std::string child(const std::string& parent, std::string_view key);
// "frames", 3 -> "frames[3]".
std::string item(const std::string& parent, std::size_t index);

class Reader {
public:
    explicit Reader(std::filesystem::path origin) : origin_(std::move(origin)) {}

    const std::filesystem::path& origin() const { return origin_; }

    // Parses a whole document (a syntax error names the line and column).
    YAML::Node load(const std::string& text) const;

    [[noreturn]] void fail(const YAML::Node& node, const std::string& field,
                           const std::string& message) const;

    // The node must be a map whose keys are plain scalars from `allowed`,
    // each at most once.
    void expect_map(const YAML::Node& node, const std::string& field,
                    std::initializer_list<std::string_view> allowed) const;
    // A map without key restrictions (duplicates still rejected).
    void expect_any_map(const YAML::Node& node, const std::string& field) const;
    void expect_list(const YAML::Node& node, const std::string& field) const;

    // map[key]; fails with "missing field" when absent.
    YAML::Node require(const YAML::Node& map, const std::string& parent,
                       std::string_view key) const;

    std::string string_value(const YAML::Node& node, const std::string& field) const;
    int int_value(const YAML::Node& node, const std::string& field) const;
    double real_value(const YAML::Node& node, const std::string& field) const;
    bool bool_value(const YAML::Node& node, const std::string& field) const;

private:
    // The scalar text of a plain (unquoted) scalar; `kind` names what was expected.
    std::string plain_scalar(const YAML::Node& node, const std::string& field,
                             const char* kind) const;
    void check_keys(const YAML::Node& node, const std::string& field,
                    std::initializer_list<std::string_view>* allowed) const;

    std::filesystem::path origin_;
};

} // namespace fpp::yaml_fields
