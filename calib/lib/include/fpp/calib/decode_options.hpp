#pragma once
// The decoder's options as a user gives them: to fpp-calib (--min-modulation,
// --threads) or to the Python package (fpp.decode(min_modulation=...,
// threads=...)). Both refuse a value with DecodeOptions::validate()'s message,
// naming the option the way that user spelt it.

#include "fpp/decoder.hpp"

#include <string>

namespace fpp::calib {

// How an option is named in the refusal.
enum class OptionSpelling {
    command_line, // "--min-modulation", "--threads" (file: "command line")
    keyword,      // "min_modulation", "threads" (file: the `origin` given)
};

// DecodeOptions::validate(), its refusal thrown again as InputError(origin,
// option, what was expected): origin "command line" and the option's flag
// for command_line; `origin` (e.g. "fpp.decode") and the keyword for
// keyword. A value of the phase-error settings is named "phase_error" (its
// message names the setting) in both.
void check_decode_options(const DecodeOptions& options,
                          OptionSpelling spelling = OptionSpelling::command_line,
                          const std::string& origin = "command line");

} // namespace fpp::calib
