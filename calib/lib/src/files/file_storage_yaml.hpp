#pragma once
// YAML (and JSON) calibration text rewritten in the shape OpenCV's own
// FileStorage writer gives it, before OpenCV's parser reads it.
//
// OpenCV 4.6's YAML parser never returns from some malformed text (three
// kinds found by tests/fuzz, each refused by its own check, and more were
// likely). Rather than chase them one at a time, the text is parsed by
// yaml-cpp's Load, fuzzed here too (fuzz_board_yaml; its LoadAll is not used:
// it never returns from text that starts with ','), and
// written again from its tree in the small grammar OpenCV writes: block maps
// with three-space indentation, the opencv-matrix tags, flow lists and flow
// maps inside lists, plain scalars of letters, digits and . + - _, every
// other scalar double-quoted. OpenCV's parser then only ever reads text of
// the shape it writes itself. Files OpenCV wrote read exactly as before.

#include <filesystem>
#include <string>

namespace fpp::calib::detail {

// `text` as yaml-cpp parses it (a leading `%YAML:1.x` line, OpenCV's own
// spelling of the directive, is accepted), written in OpenCV's grammar.
// Throws InputError(origin, "line N", ...) for text that is not YAML, and
// InputError(origin, ...) for more than one document, a top level that is not
// a map, a key OpenCV would not write, a control character in a string,
// nesting deeper than 16 or text that grows, written again, past four times
// its length and 4 KB (only aliases can).
std::string rewrite_yaml_for_opencv(const std::string& text, const std::filesystem::path& origin);

} // namespace fpp::calib::detail
