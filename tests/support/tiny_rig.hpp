#pragma once
// The paper rig with its effects, both images binned (camera 16 x 16 to
// 100 x 75, projector 8 x 8 to 160 x 100): rendering a frame costs in
// proportion to the camera and the projector image (at 1280 x 800 the
// projector's defocus took 90 % of the time), so a scan takes milliseconds.
// Scaled with the pixels, both defocus sigmas fall to 0.1 px and below,
// where the blur is the identity: they are set to 0, which skips it.
// Pixel centres on integers: c' = (c + 0.5) / k - 0.5. For tests of many
// scans (stress, soak, power cuts). Header-only: it needs fpp_sim.
#include "fpp/simulator/rig.hpp"
#include "test_support.hpp"

namespace fpp::test {

inline constexpr int kTinyCameraBinning = 16;   // 1600 x 1200 -> 100 x 75
inline constexpr int kTinyProjectorBinning = 8; // 1280 x 800 -> 160 x 100

inline sim::Rig tiny_rig() {
    sim::Rig rig = sim::load_rig(source_dir() / "board/sim/paper-rig-effects.yaml")
                       .binned_camera(kTinyCameraBinning);
    constexpr int k = kTinyProjectorBinning;
    rig.name += "-small";
    rig.projector_size = {rig.projector_size.width / k, rig.projector_size.height / k};
    rig.projector.fu /= k;
    rig.projector.fv /= k;
    rig.projector.skew /= k;
    rig.projector.cu = (rig.projector.cu + 0.5) / k - 0.5;
    rig.projector.cv = (rig.projector.cv + 0.5) / k - 0.5;
    rig.projector_optics.defocus_sigma_px = 0;
    rig.sensor.defocus_sigma_px = 0;
    return rig;
}

} // namespace fpp::test
