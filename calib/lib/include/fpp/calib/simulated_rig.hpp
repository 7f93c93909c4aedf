#pragma once
// The exact calibrations of the virtual scanner's rigs: what a perfect
// calibration of each would give. For the host tool's simulations
// (fpp_calib_sim) and the tests; the calibration and reconstruction
// libraries do not depend on the simulator. Header-only, so that the tests
// of the calibration files' library (built alone under the sanitizers) use
// it without the rest.
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/two_camera.hpp"
#include "fpp/simulator/camera_pair_rig.hpp"
#include "fpp/simulator/rig.hpp"

namespace fpp::calib {

// The stereo model of a simulated rig (its lenses, R and t; sizes from the
// rig). With rig.without_effects() the simulator renders exactly this
// model. Pose list empty, RMS unknown.
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

// The true camera-camera calibration of a simulated pair (lenses with every
// term, sizes, R, T; origin "virtual scanner").
inline CameraPairCalibration true_camera_pair(const sim::CameraPairRig& rig) {
    CameraPairCalibration c;
    c.first_size = rig.first.camera_size;
    c.second_size = rig.second.camera_size;
    c.first = rig.first.camera;
    c.second = rig.second.camera;
    c.R = rig.R;
    c.T = rig.T;
    c.rms = 0;
    c.origin = "virtual scanner (true geometry of " + rig.first.name + " and its second camera)";
    return c;
}

} // namespace fpp::calib
