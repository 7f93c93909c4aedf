#pragma once
// The turn between a calibration's camera frame and a camera model's frame
// (the simulator's truth), measured from the two cameras' rays alone.
//
// A camera lens defect outside the calibration's model can have a part that
// moves the image as a small turn of the camera does (with a principal point
// shift). No image of any board tells the two apart: the calibration then
// holds the whole rig turned about the camera centre by that much, with every
// shape and length intact. This measures that turn, so that an evaluation can
// report the error against the truth in the true frame's orientation BESIDE
// the error with nothing removed (never instead of it).

#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/lens_model.hpp"

#include <vector>

namespace fpp::calib {

struct FrameTurn {
    // X_true = Q X_calibrated (camera frames, the camera centre fixed).
    Mat3 Q{1, 0, 0, 0, 1, 0, 0, 0, 1};
    double angle_rad = 0;   // Q's angle of rotation
    double ray_rms_rad = 0; // angle between the turned calibrated rays and the true ones, RMS
    int rays = 0;           // pixels compared
};

// Least squares over the unit rays of every `step_px`-th pixel of the
// calibration's camera image where both models give a ray (Kabsch): the
// rotation that best maps the calibrated rays onto `true_camera`'s. Throws
// std::invalid_argument when fewer than 3 pixels have both rays or step_px < 1.
FrameTurn camera_frame_turn(const StereoCalibration& calibration, const LensModel& true_camera,
                            int step_px = 8);

// `points` (camera frame, mm) turned by `turn`'s Q about the camera centre.
void turn_points(const FrameTurn& turn, std::vector<Vec3>& points);

} // namespace fpp::calib
