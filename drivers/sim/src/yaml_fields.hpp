#pragma once
// Strict reading of the simulator's YAML files (rigs, scenes): every
// rejection names the file and the dotted field path. Internal to fpp_sim.

#include "fpp/error.hpp"

#include <yaml-cpp/yaml.h>

#include <array>
#include <filesystem>
#include <initializer_list>
#include <string>

namespace fpp::sim::detail {

class YamlFields {
  public:
    explicit YamlFields(std::filesystem::path file) : file_(std::move(file)) {}

    const std::filesystem::path& file() const { return file_; }

    // Parses the whole file; a missing or unparsable file is an InputError.
    YAML::Node load() const;

    [[noreturn]] void fail(const std::string& field, const std::string& what) const {
        throw InputError(file_, field, what);
    }

    // `node` (at `field`) must be a map whose keys are all in `allowed`, each once.
    void expect_map(const YAML::Node& node, const std::string& field,
                    std::initializer_list<const char*> allowed) const;
    // The child `key` of map `node`; throws if absent.
    YAML::Node require(const YAML::Node& node, const std::string& field, const char* key) const;

    double number(const YAML::Node& node, const std::string& field) const;
    double number(const YAML::Node& map, const std::string& field, const char* key,
                  double default_value) const;
    int integer(const YAML::Node& node, const std::string& field) const;
    bool boolean(const YAML::Node& node, const std::string& field) const;
    std::string string(const YAML::Node& node, const std::string& field) const;

    template <std::size_t N>
    std::array<double, N> vector(const YAML::Node& node, const std::string& field) const {
        if (!node.IsSequence() || node.size() != N)
            fail(field, "expected a list of " + std::to_string(N) + " numbers");
        std::array<double, N> v{};
        for (std::size_t i = 0; i < N; ++i)
            v[i] = number(node[i], field + "[" + std::to_string(i) + "]");
        return v;
    }

    static std::string join(const std::string& parent, const std::string& key) {
        return parent.empty() ? key : parent + "." + key;
    }

  private:
    std::filesystem::path file_;
};

// Shortest text that reads back to the same double.
std::string format_number(double v);

} // namespace fpp::sim::detail
