#pragma once
// The `name = value` text that Bouguet's toolbox prints for a stereo
// calibration and that MATLAB's mat2str writes: one field a line, a number or
// a bracketed matrix with ';' between rows. Private to the calibration readers.

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace fpp::calib::detail {

struct TextMatrix {
    int rows = 0;
    int cols = 0;
    std::vector<double> values; // row-major
    int line = 0;               // 1-based line of the file
    double at(int r, int c) const { return values[std::size_t(r * cols + c)]; }
};

using TextFields = std::map<std::string, TextMatrix>;

// Each line: optional comment marks (% or #) and text, then `name = value`,
// then anything (Bouguet's "± [ uncertainties ]", MATLAB's "; % comment").
// Lines without '=' are skipped. Throws InputError(origin, "line N", ...) for
// a malformed value, ragged rows or a name given twice.
TextFields parse_text_fields(const std::string& text, const std::filesystem::path& origin);

} // namespace fpp::calib::detail
