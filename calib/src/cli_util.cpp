#include "cli_util.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/sequences.hpp"

namespace fpp::calib {

Sequence sequence_from_argument(const std::string& name_or_path, Size projector) {
    if (std::filesystem::is_regular_file(name_or_path)) return read_sequence(name_or_path);
    return standard_sequence(name_or_path, projector);
}

} // namespace fpp::calib
