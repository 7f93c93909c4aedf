// The true camera-camera calibration of the virtual scanner's binocular rig
// (fpp/calib/two_camera.hpp).

#include "fpp/calib/two_camera.hpp"

#include "fpp/sim/camera_pair_rig.hpp"

namespace fpp::calib {

CameraPairCalibration true_camera_pair(const sim::CameraPairRig& rig) {
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
