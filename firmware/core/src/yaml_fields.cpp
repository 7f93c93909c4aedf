#include "fpp/yaml_fields.hpp"

#include "fpp/enum_names.hpp"
#include "fpp/error.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <system_error>

namespace fpp::yaml_fields {

namespace {

constexpr EnumName<YAML::NodeType::value> kNodeTypeTexts[] = {
    {YAML::NodeType::Null, "nothing (null)"},
    {YAML::NodeType::Scalar, "a scalar"},
    {YAML::NodeType::Sequence, "a list"},
    {YAML::NodeType::Map, "a map"},
};

const char* describe_type(const YAML::Node& node) {
    return name_of(kNodeTypeTexts, node.Type(), "nothing");
}

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

bool is_digit(char c) {
    return c >= '0' && c <= '9';
}

// YAML 1.2 core-schema decimal integer: [-+]?[0-9]+
bool is_decimal_integer(const std::string& s) {
    std::size_t i = (!s.empty() && (s[0] == '-' || s[0] == '+')) ? 1 : 0;
    if (i == s.size())
        return false;
    for (; i < s.size(); ++i) {
        if (!is_digit(s[i]))
            return false;
    }
    return true;
}

// YAML 1.2 core-schema float, finite forms only:
// [-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?
bool is_finite_real_syntax(const std::string& s) {
    std::size_t i = 0;
    if (i < s.size() && (s[i] == '-' || s[i] == '+'))
        ++i;
    std::size_t digits = 0;
    while (i < s.size() && is_digit(s[i]))
        ++i, ++digits;
    if (i < s.size() && s[i] == '.') {
        ++i;
        while (i < s.size() && is_digit(s[i]))
            ++i, ++digits;
    }
    if (digits == 0)
        return false;
    if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
        ++i;
        if (i < s.size() && (s[i] == '-' || s[i] == '+'))
            ++i;
        std::size_t exponent_digits = 0;
        while (i < s.size() && is_digit(s[i]))
            ++i, ++exponent_digits;
        if (exponent_digits == 0)
            return false;
    }
    return i == s.size();
}

bool is_non_finite_word(const std::string& s) {
    std::string t = lower(s);
    if (!t.empty() && (t[0] == '-' || t[0] == '+'))
        t.erase(0, 1);
    return t == ".inf" || t == ".nan" || t == "inf" || t == "nan" || t == "infinity";
}

// True if `s` can be written unquoted and reads back as the same string.
bool is_plain_safe(const std::string& s) {
    if (s.empty())
        return false;
    for (const char c : s) {
        const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || is_digit(c) ||
                        c == '_' || c == '.' || c == '-' || c == '/' || c == '+';
        if (!ok)
            return false;
    }
    if (s[0] == '-' || s[0] == '+' || s[0] == '.')
        return false;
    // Would read back as a number, boolean or null in other YAML readers.
    static const std::set<std::string> words = {"true", "false", "null", "yes", "no",
                                                "on",   "off",   "y",    "n"};
    if (words.count(lower(s)))
        return false;
    if (std::all_of(s.begin(), s.end(), is_digit))
        return false;
    double ignored = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), ignored);
    return !(ec == std::errc() && end == s.data() + s.size());
}

} // namespace

std::string child(const std::string& parent, std::string_view key) {
    return parent.empty() ? std::string(key) : parent + "." + std::string(key);
}

std::string item(const std::string& parent, std::size_t index) {
    return parent + "[" + std::to_string(index) + "]";
}

std::string read_text_file(const std::filesystem::path& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        throw InputError(path, "", "is a folder, not a file");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw InputError(path, "", std::string("cannot open: ") + std::strerror(errno));
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad())
        throw InputError(path, "", "read error");
    return text.str();
}

YAML::Node Reader::load(const std::string& text) const {
    try {
        return YAML::Load(text);
    } catch (const YAML::Exception& e) {
        std::string where;
        if (!e.mark.is_null()) {
            where = " at line " + std::to_string(e.mark.line + 1) + ", column " +
                    std::to_string(e.mark.column + 1);
        }
        throw InputError(origin_, "", "not valid YAML" + where + ": " + e.msg);
    }
}

YAML::Node Reader::load_file() const {
    return load(read_text_file(origin_));
}

void Reader::fail(const YAML::Node& node, const std::string& field,
                  const std::string& message) const {
    std::string where;
    if (node.IsDefined() && !node.Mark().is_null()) {
        where = " (line " + std::to_string(node.Mark().line + 1) + ")";
    }
    throw InputError(origin_, field, message + where);
}

void Reader::fail(const std::string& field, const std::string& message) const {
    throw InputError(origin_, field, message);
}

void Reader::check_keys(const YAML::Node& node, const std::string& field,
                        std::initializer_list<std::string_view>* allowed) const {
    if (!node.IsMap()) {
        fail(node, field, std::string("must be a map, got ") + describe_type(node));
    }
    std::set<std::string> seen;
    for (auto it = node.begin(); it != node.end(); ++it) {
        const YAML::Node key = it->first; // a copy: `it->` points into a temporary
        if (!key.IsScalar())
            fail(key, field, "map keys must be plain names");
        const std::string& name = key.Scalar();
        if (!seen.insert(name).second)
            fail(key, child(field, name), "key given twice");
        if (allowed &&
            std::find(allowed->begin(), allowed->end(), std::string_view(name)) == allowed->end()) {
            std::string list;
            for (auto a : *allowed)
                list += (list.empty() ? "" : ", ") + std::string(a);
            fail(key, child(field, name), "unknown key (allowed here: " + list + ")");
        }
    }
}

void Reader::expect_map(const YAML::Node& node, const std::string& field,
                        std::initializer_list<std::string_view> allowed) const {
    check_keys(node, field, &allowed);
}

void Reader::expect_any_map(const YAML::Node& node, const std::string& field) const {
    check_keys(node, field, nullptr);
}

void Reader::expect_list(const YAML::Node& node, const std::string& field) const {
    if (!node.IsSequence()) {
        fail(node, field, std::string("must be a list, got ") + describe_type(node));
    }
}

void Reader::expect_list(const YAML::Node& node, const std::string& field, std::size_t size) const {
    expect_list(node, field);
    if (node.size() != size) {
        fail(node, field,
             "must be a list of " + std::to_string(size) + " values, got " +
                 std::to_string(node.size()));
    }
}

YAML::Node Reader::require(const YAML::Node& map, const std::string& parent,
                           std::string_view key) const {
    const YAML::Node value = map[std::string(key)];
    if (!value.IsDefined())
        fail(map, child(parent, key), "missing field");
    return value;
}

std::string Reader::plain_scalar(const YAML::Node& node, const std::string& field,
                                 const char* kind) const {
    if (!node.IsScalar()) {
        fail(node, field, std::string("must be ") + kind + ", got " + describe_type(node));
    }
    if (node.Tag() != "?") {
        fail(node, field,
             std::string("must be ") + kind + ", got the quoted or tagged text '" + node.Scalar() +
                 "'");
    }
    return node.Scalar();
}

std::string Reader::string_value(const YAML::Node& node, const std::string& field) const {
    if (!node.IsScalar())
        fail(node, field, std::string("must be text, got ") + describe_type(node));
    return node.Scalar();
}

int Reader::int_value(const YAML::Node& node, const std::string& field) const {
    const std::string text = plain_scalar(node, field, "an integer");
    if (!is_decimal_integer(text)) {
        if (is_non_finite_word(text))
            fail(node, field, "non-finite number '" + text + "'");
        fail(node, field, "must be an integer, got '" + text + "'");
    }
    const std::size_t start = text[0] == '+' ? 1 : 0;
    long long value = 0;
    const auto [end, ec] = std::from_chars(text.data() + start, text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size() ||
        value < std::numeric_limits<int>::min() || value > std::numeric_limits<int>::max()) {
        fail(node, field, "integer out of range: '" + text + "'");
    }
    return static_cast<int>(value);
}

double Reader::real_value(const YAML::Node& node, const std::string& field) const {
    const std::string text = plain_scalar(node, field, "a number");
    if (is_non_finite_word(text))
        fail(node, field, "non-finite number '" + text + "'");
    if (!is_finite_real_syntax(text))
        fail(node, field, "must be a number, got '" + text + "'");
    const std::size_t start = text[0] == '+' ? 1 : 0;
    double value = 0;
    const auto [end, ec] = std::from_chars(text.data() + start, text.data() + text.size(), value);
    if (ec == std::errc::result_out_of_range || (ec == std::errc() && !std::isfinite(value))) {
        fail(node, field, "number out of the double range: '" + text + "'");
    }
    if (ec != std::errc() || end != text.data() + text.size()) {
        fail(node, field, "must be a number, got '" + text + "'");
    }
    return value;
}

double Reader::real_or_ratio_value(const YAML::Node& node, const std::string& field) const {
    const std::string text = plain_scalar(node, field, "a number or a ratio such as 1920/58");
    const auto slash = text.find('/');
    if (slash == std::string::npos)
        return real_value(node, field);
    const std::string parts[2] = {text.substr(0, slash), text.substr(slash + 1)};
    double values[2] = {0, 0};
    for (int k = 0; k < 2; ++k) {
        const std::string& part = parts[k];
        const std::size_t start = !part.empty() && part[0] == '+' ? 1 : 0;
        const auto [end, ec] =
            std::from_chars(part.data() + start, part.data() + part.size(), values[k]);
        if (!is_finite_real_syntax(part) || ec != std::errc() || end != part.data() + part.size() ||
            !std::isfinite(values[k])) {
            fail(node, field,
                 "must be a number or a ratio of two numbers such as 1920/58, got '" + text + "'");
        }
    }
    if (values[1] == 0.0)
        fail(node, field, "ratio '" + text + "' divides by zero");
    const double value = values[0] / values[1];
    if (!std::isfinite(value))
        fail(node, field, "ratio '" + text + "' is out of the double range");
    return value;
}

bool Reader::bool_value(const YAML::Node& node, const std::string& field) const {
    const std::string text = plain_scalar(node, field, "true or false");
    if (text == "true" || text == "True" || text == "TRUE")
        return true;
    if (text == "false" || text == "False" || text == "FALSE")
        return false;
    fail(node, field, "must be true or false, got '" + text + "'");
}

double Reader::real_value_or(const YAML::Node& map, const std::string& parent, std::string_view key,
                             double fallback) const {
    const YAML::Node value = map[std::string(key)];
    if (!value.IsDefined())
        return fallback;
    return real_value(value, child(parent, key));
}

std::string format_real(double value) {
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    std::string text(buffer, result.ptr);
    if (text.find_first_of(".eEn") == std::string::npos)
        text += ".0";
    return text;
}

std::string format_string(const std::string& text) {
    if (is_plain_safe(text))
        return text;
    std::string out = "\"";
    for (const char c : text) {
        const auto u = static_cast<unsigned char>(c);
        if (c == '"' || c == '\\') {
            out += '\\';
            out += c;
        } else if (u < 0x20 || u == 0x7f) {
            static const char* hex = "0123456789abcdef";
            out += "\\x";
            out += hex[u >> 4];
            out += hex[u & 15];
        } else {
            out += c;
        }
    }
    return out + "\"";
}

} // namespace fpp::yaml_fields
