#pragma once
// Named pattern sequences, so that people and tests can ask for a standard
// scan without writing YAML.

#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

#include <string>
#include <vector>

namespace fpp {

// Names:
//   "gray-xy"        white, black, 8-step phase (period 20) + complementary Gray, x then y (default)
//   "gray-x"         the same, x only
//   "plain-gray-x"   white, black, 8-step phase + plain Gray code, x
//   "inverse-gray-x" 8-step phase + Gray code with inverse frames, x
//   "multi-period-x" 8-step phase at periods 20, 160 and one period over the whole projector
//   "heterodyne-x"   three-frequency heterodyne, 8-step phase at periods 20, 21, 22.1...
//   "centerline-xy"  the paper's: white, 8-step phase + centerline frame, x then y
// Throws std::invalid_argument for an unknown name.
Sequence standard_sequence(const std::string& name, Size projector);
std::vector<std::string> standard_sequence_names();

} // namespace fpp
