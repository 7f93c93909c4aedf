#include "cli_util.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/sequences.hpp"

#include <cstdio>

namespace fpp::calib {

Sequence sequence_from_argument(const std::string& name_or_path, Size projector) {
    if (std::filesystem::is_regular_file(name_or_path)) return read_sequence(name_or_path);
    return standard_sequence(name_or_path, projector);
}

std::string seconds_text(double seconds) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f s", seconds);
    return text;
}

} // namespace fpp::calib
