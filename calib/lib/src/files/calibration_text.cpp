// The `name = value` text of Bouguet's and MATLAB's stereo results
// (calibration_text.hpp).

#include "calibration_text.hpp"

#include "fpp/error.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace fpp::calib::detail {

namespace {

bool name_char(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.';
}

// One number at text[pos...]; advances pos. False if none.
bool read_number(const std::string& text, std::size_t& pos, double& value) {
    const char* begin = text.c_str() + pos;
    char* end = nullptr;
    value = std::strtod(begin, &end);
    if (end == begin)
        return false;
    pos += static_cast<std::size_t>(end - begin);
    return true;
}

} // namespace

TextFields parse_text_fields(const std::string& text, const std::filesystem::path& origin) {
    TextFields fields;
    std::istringstream lines(text);
    std::string line;
    int number = 0;
    while (std::getline(lines, line)) {
        ++number;
        const std::string where = "line " + std::to_string(number);
        const std::size_t eq = line.find('=');
        if (eq == std::string::npos || eq == 0)
            continue;
        // The name: the identifier just before '=' (text before it is a label).
        std::size_t name_end = eq;
        while (name_end > 0 && line[name_end - 1] == ' ')
            --name_end;
        std::size_t name_begin = name_end;
        while (name_begin > 0 && name_char(line[name_begin - 1]))
            --name_begin;
        if (name_begin == name_end)
            continue;
        const std::string name = line.substr(name_begin, name_end - name_begin);
        if (std::isdigit(static_cast<unsigned char>(name[0])) != 0)
            continue;

        TextMatrix m;
        m.line = number;
        std::size_t pos = eq + 1;
        while (pos < line.size() && line[pos] == ' ')
            ++pos;
        if (pos < line.size() && line[pos] == '[') {
            const std::size_t close = line.find(']', pos);
            if (close == std::string::npos)
                throw InputError(origin, where, "'" + name + "': '[' without ']' on the line");
            std::size_t p = pos + 1;
            int cols_in_row = 0;
            while (p < close) {
                const char c = line[p];
                if (c == ' ' || c == ',' || c == '\t' || c == '\r') {
                    ++p;
                } else if (c == ';') {
                    if (cols_in_row == 0 || cols_in_row != m.cols)
                        throw InputError(origin, where,
                                         "'" + name + "': rows of different lengths");
                    ++m.rows;
                    cols_in_row = 0;
                    ++p;
                } else {
                    double v = 0;
                    if (!read_number(line, p, v) || p > close || !std::isfinite(v))
                        throw InputError(origin, where,
                                         "'" + name + "': expected numbers inside [ ]");
                    m.values.push_back(v);
                    ++cols_in_row;
                    if (m.rows == 0)
                        m.cols = cols_in_row;
                }
            }
            // Close the last row (a row ends at ';' or ']'; a trailing ';' adds none).
            if (cols_in_row > 0) {
                if (m.rows > 0 && cols_in_row != m.cols)
                    throw InputError(origin, where, "'" + name + "': rows of different lengths");
                ++m.rows;
            }
            if (m.rows == 0 && !m.values.empty())
                m.rows = 1;
            // A matrix written with ';' rows: the first row set cols; recount.
            if (m.rows > 0 && m.cols > 0 && m.values.size() != std::size_t(m.rows * m.cols))
                throw InputError(origin, where, "'" + name + "': rows of different lengths");
        } else {
            double v = 0;
            if (!read_number(line, pos, v))
                continue; // not a numeric field (a string, a struct): not ours
            if (!std::isfinite(v))
                throw InputError(origin, where, "'" + name + "': not a finite number");
            m.rows = m.cols = 1;
            m.values.push_back(v);
        }
        if (m.values.empty())
            throw InputError(origin, where, "'" + name + "': empty matrix");
        if (!fields.emplace(name, std::move(m)).second)
            throw InputError(origin, where, "'" + name + "' given twice");
    }
    return fields;
}

} // namespace fpp::calib::detail
