#include "yaml_fields.hpp"

#include <charconv>
#include <cmath>
#include <set>
#include <system_error>

namespace fpp::sim::detail {

YAML::Node YamlFields::load() const {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file_, ec))
        fail("", "no such file");
    try {
        return YAML::LoadFile(file_.string());
    } catch (const YAML::Exception& e) {
        fail("", std::string("not valid YAML: ") + e.what());
    }
}

void YamlFields::expect_map(const YAML::Node& node, const std::string& field,
                            std::initializer_list<const char*> allowed) const {
    if (!node.IsMap())
        fail(field.empty() ? "(top level)" : field, "expected a map");
    std::set<std::string> seen;
    for (const auto& kv : node) {
        if (!kv.first.IsScalar())
            fail(field, "keys must be plain words");
        const std::string key = kv.first.Scalar();
        bool known = false;
        for (const char* a : allowed)
            known = known || key == a;
        if (!known)
            fail(join(field, key), "unknown key");
        if (!seen.insert(key).second)
            fail(join(field, key), "duplicate key");
    }
}

YAML::Node YamlFields::require(const YAML::Node& node, const std::string& field,
                               const char* key) const {
    const YAML::Node child = node[key];
    if (!child.IsDefined() || child.IsNull())
        fail(join(field, key), "missing required field");
    return child;
}

double YamlFields::number(const YAML::Node& node, const std::string& field) const {
    if (!node.IsScalar())
        fail(field, "expected a number");
    const std::string& text = node.Scalar();
    double v = 0;
    // yaml-cpp accepts .nan/.inf; plain strtod forms too. Parse ourselves so
    // that every non-finite spelling is caught the same way.
    const char* begin = text.data();
    const char* end = text.data() + text.size();
    if (begin != end && *begin == '+')
        ++begin;
    const auto [ptr, ec] = std::from_chars(begin, end, v);
    if (ec != std::errc() || ptr != end) {
        if (text == ".nan" || text == ".NaN" || text == ".NAN" || text == "nan" ||
            text.find("inf") != std::string::npos || text.find("Inf") != std::string::npos ||
            text.find("INF") != std::string::npos)
            fail(field, "must be a finite number, got '" + text + "'");
        fail(field, "expected a number, got '" + text + "'");
    }
    if (!std::isfinite(v))
        fail(field, "must be a finite number, got '" + text + "'");
    return v;
}

double YamlFields::number(const YAML::Node& map, const std::string& field, const char* key,
                          double default_value) const {
    const YAML::Node child = map[key];
    if (!child.IsDefined())
        return default_value;
    return number(child, join(field, key));
}

int YamlFields::integer(const YAML::Node& node, const std::string& field) const {
    const double v = number(node, field);
    if (v != std::floor(v) || std::fabs(v) > 1e9)
        fail(field, "expected an integer");
    return static_cast<int>(v);
}

bool YamlFields::boolean(const YAML::Node& node, const std::string& field) const {
    if (!node.IsScalar())
        fail(field, "expected true or false");
    const std::string& s = node.Scalar();
    if (s == "true")
        return true;
    if (s == "false")
        return false;
    fail(field, "expected true or false, got '" + s + "'");
}

std::string YamlFields::string(const YAML::Node& node, const std::string& field) const {
    if (!node.IsScalar())
        fail(field, "expected a text value");
    return node.Scalar();
}

std::string format_number(double v) {
    char buf[64];
    const auto res = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, res.ptr);
}

} // namespace fpp::sim::detail
