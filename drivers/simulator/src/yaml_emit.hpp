#pragma once
// Writing the simulator's YAML (rigs, session boards, pose metadata) with
// yaml-cpp's emitter (internal). Reals go out as yaml_fields::format_real's
// text, the shortest that reads back to the same double, rather than as the
// emitter's own fixed-precision spelling.

#include "fpp/yaml_fields.hpp"

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <initializer_list>

namespace fpp::sim::yaml_emit {

inline void real(YAML::Emitter& out, double value) {
    out << yaml_fields::format_real(value);
}

// [a, b, ...] on one line.
inline void flow_reals(YAML::Emitter& out, const double* values, std::size_t count) {
    out << YAML::Flow << YAML::BeginSeq;
    for (std::size_t i = 0; i < count; ++i)
        real(out, values[i]);
    out << YAML::EndSeq;
}
inline void flow_reals(YAML::Emitter& out, std::initializer_list<double> values) {
    flow_reals(out, values.begin(), values.size());
}

// The document as text, ending with a newline as every file we write does.
inline std::string document(const YAML::Emitter& out) {
    return std::string(out.c_str()) + "\n";
}

} // namespace fpp::sim::yaml_emit
