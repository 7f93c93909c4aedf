#pragma once
// A second camera for the virtual scanner: two cameras and one projector (the
// layout of binocular heads, the projector only a texture).
//
// Frames: the first camera's frame is the world frame, mm; scenes are built
// in it. The second camera is reached by X_2 = R X_1 + T (as in
// fpp::calib::CameraPairCalibration). Each camera gets its own sim::Rig whose
// projector pose is the same physical projector seen from that camera, so the
// renderer needs no change: the second camera renders the scene moved into
// its frame (scene_seen_from).

#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <memory>

namespace fpp::sim {

struct CameraPairRig {
    Rig first;  // camera 1 and the projector (X_p = first.R X_1 + first.t)
    Rig second; // camera 2 and the same projector (X_p = second.R X_2 + second.t)
    Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1}; // X_2 = R X_1 + T
    Vec3 T{0, 0, 0};                   // mm
};

// The rig of a second camera (lens `camera`, image `camera_size`, pose
// X_2 = R X_1 + T) beside `first`'s camera, lit by `first`'s projector; the
// sensor, projector and optics are `first`'s.
Rig second_camera_rig(const Rig& first, const LensModel& camera, Size camera_size, const Mat3& R,
                      const Vec3& T);

// Two cameras on either side of `first`'s projector: the second camera's
// centre `baseline_mm` along the first camera's +x axis, turned (about its own
// y axis, then rows kept level) to look at (0, 0, converge_mm) of the first
// camera's frame; its lens is the first's with slightly different intrinsics
// (focal lengths +0.4 %, principal point (+9, -6) px, k1 -0.01) so that the
// two are not interchangeable. Throws std::invalid_argument for a baseline
// or distance that is not positive.
CameraPairRig binocular_rig(const Rig& first, double baseline_mm = 250.0,
                            double converge_mm = 480.0);

// Both cameras binned `factor` x `factor` (Rig::binned_camera); R, T unchanged.
CameraPairRig binned(const CameraPairRig& pair, int factor);

// `scene` (first camera's frame) as the second camera sees it: every object
// moved by X_2 = R X_1 + T, with the same index, name and specular lobe. The
// returned scene shares `scene`, which must not change afterwards.
Scene scene_seen_from(std::shared_ptr<const Scene> scene, const Mat3& R, const Vec3& T);

} // namespace fpp::sim
