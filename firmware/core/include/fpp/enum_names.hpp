#pragma once
// Names of enum values, from one table per enum.
//
// An enum whose values are written as text (files, options, log lines,
// messages) declares one constexpr table of {value, name} pairs next to its
// functions; its to_string, its parser and the list of names in the parser's
// error message are all read from that table, so the name printed, the name
// parsed and the names the message offers cannot disagree. (A switch one
// way and an if-chain the other spelt each name two or three times.)
//
// A table has no -Wswitch: tests/unit/core/test_enum_names.cpp checks that
// every value of the core's enums has a name that reads back, and the tests
// of calib's modules (sv_reconstruct, hybrid_calibrate, camera_pair,
// stereo_calibrate, session_check) do so for theirs.
//
//   inline constexpr EnumName<Axes> kAxesNames[] = {{Axes::x, "x"}, {Axes::xy, "xy"}};
//   name_of(kAxesNames, Axes::xy)      "xy" ("?" for a value not in the table)
//   value_of(kAxesNames, "x")          Axes::x (std::nullopt for an unknown name)
//   names_list(kAxesNames)             "x, xy" (names_list(kAxesNames, " or "): "x or xy")
//   parse_name(kAxesNames, "axes", "z") throws std::invalid_argument "unknown axes 'z' (x, xy)"

#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace fpp {

template <class Enum> struct EnumName {
    Enum value;
    const char* name;
};

// The name of `value` in `table`; `fallback` for a value not in it.
template <class Enum, std::size_t N>
constexpr const char* name_of(const EnumName<Enum> (&table)[N], Enum value,
                              const char* fallback = "?") {
    for (const EnumName<Enum>& entry : table)
        if (entry.value == value)
            return entry.name;
    return fallback;
}

// The value named `name` (the whole name, case and all), or nothing.
template <class Enum, std::size_t N>
constexpr std::optional<Enum> value_of(const EnumName<Enum> (&table)[N], std::string_view name) {
    for (const EnumName<Enum>& entry : table)
        if (name == entry.name)
            return entry.value;
    return std::nullopt;
}

// The names in the table's order, for a message: "auto, x, xy"; `last` goes
// before the last name instead of ", " (" or ": "polynomial, ray or rational").
template <class Enum, std::size_t N>
std::string names_list(const EnumName<Enum> (&table)[N], std::string_view last = ", ") {
    std::string list;
    for (std::size_t i = 0; i < N; ++i) {
        if (i > 0)
            list += i + 1 == N ? last : std::string_view(", ");
        list += table[i].name;
    }
    return list;
}

// The message for a name not in the table: "unknown <what> '<name>' (<names>)",
// the names as names_list(table, last) gives them.
template <class Enum, std::size_t N>
std::string unknown_name_message(const EnumName<Enum> (&table)[N], std::string_view what,
                                 std::string_view name, std::string_view last = ", ") {
    std::string message = "unknown ";
    message += what;
    message += " '";
    message += name;
    message += "' (";
    message += names_list(table, last);
    message += ")";
    return message;
}

// The value named `name`; std::invalid_argument with unknown_name_message
// for any other name.
template <class Enum, std::size_t N>
Enum parse_name(const EnumName<Enum> (&table)[N], std::string_view what, std::string_view name,
                std::string_view last = ", ") {
    if (const std::optional<Enum> value = value_of(table, name))
        return *value;
    throw std::invalid_argument(unknown_name_message(table, what, name, last));
}

} // namespace fpp
