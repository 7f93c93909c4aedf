#pragma once
// The exact stereo model of a simulated rig (its lenses, R and t; sizes from
// the rig): what a perfect calibration of it would give. With
// rig.without_effects() the simulator renders exactly this model. Pose list
// empty, RMS unknown. Header-only: the calibration files' library does not
// depend on the simulator.

#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/sim/rig.hpp"

namespace fpp::calib {

inline StereoCalibration calibration_from_rig(const sim::Rig& rig) {
    StereoCalibration c;
    c.camera_size = rig.camera_size;
    c.projector_size = rig.projector_size;
    c.camera = rig.camera;
    c.projector = rig.projector;
    c.R = rig.R;
    c.T = rig.t;
    c.origin = "simulated rig '" + rig.name + "' (exact model)";
    return c;
}

} // namespace fpp::calib
