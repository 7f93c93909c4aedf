// The exact calibrations of the virtual scanner's rigs
// (fpp/calib/simulated_rig.hpp): the stereo model of a rig and the true
// camera-camera calibration of a pair carry the rig's lenses, sizes and pose
// as they are, and say where they come from.

#include "fpp/calib/simulated_rig.hpp"

#include "lens_expect.hpp"

#include <gtest/gtest.h>

namespace {

using fpp::test::expect_same_lens;

TEST(SimulatedRig, TheStereoModelOfARigIsItsLensesSizesAndPose) {
    const fpp::sim::Rig rig = fpp::sim::load_rig(fpp::sim::effects_rig_path());
    const fpp::calib::StereoCalibration c = fpp::calib::calibration_from_rig(rig);
    EXPECT_EQ(c.camera_size, rig.camera_size);
    EXPECT_EQ(c.projector_size, rig.projector_size);
    expect_same_lens(c.camera, rig.camera);
    expect_same_lens(c.projector, rig.projector);
    EXPECT_EQ(c.R, rig.R);
    EXPECT_EQ(c.T, rig.t);
    EXPECT_EQ(c.origin, "simulated rig '" + rig.name + "' (exact model)");
    // A binned camera's model is the binned rig's.
    const fpp::sim::Rig binned = rig.binned_camera(4);
    expect_same_lens(fpp::calib::calibration_from_rig(binned).camera, binned.camera);
    EXPECT_EQ(fpp::calib::calibration_from_rig(binned).camera_size, binned.camera_size);
}

TEST(SimulatedRig, TheTrueCameraPairIsThePairsGeometry) {
    const fpp::sim::CameraPairRig pair = fpp::sim::binocular_rig(fpp::sim::Rig::paper());
    const fpp::calib::CameraPairCalibration c = fpp::calib::true_camera_pair(pair);
    EXPECT_EQ(c.first_size, pair.first.camera_size);
    EXPECT_EQ(c.second_size, pair.second.camera_size);
    expect_same_lens(c.first, pair.first.camera);
    expect_same_lens(c.second, pair.second.camera);
    EXPECT_EQ(c.R, pair.R);
    EXPECT_EQ(c.T, pair.T);
    EXPECT_EQ(c.rms, 0.0);
    EXPECT_NEAR(c.baseline(), 250.0, 1e-9); // binocular_rig's default baseline
    EXPECT_EQ(c.origin,
              "virtual scanner (true geometry of " + pair.first.name + " and its second camera)");
}

} // namespace
