#pragma once
// The simulate commands' rig (simulate, simulate-session, demo): the only
// command files that use the simulator (fpp_calib_sim, drivers/simulator).
#include "fpp/simulator/rig.hpp"

#include <string>

namespace fpp::calib {

// The rig of `path` with the simulate commands' options applied: without its
// effects, another read noise (DN, when >= 0), the camera binned (when > 1).
sim::Rig rig_from_options(const std::string& path, bool no_effects, double read_noise, int binning);

} // namespace fpp::calib
