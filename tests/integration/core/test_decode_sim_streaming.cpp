// The streaming decoder on a simulated capture of the paper's rig (effects
// off, read noise 1.5 DN; 2 x 2 binned where tests run slowly,
// test_support.hpp): frame by frame it gives the batch result bit for bit.

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/sequences.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <type_traits>

namespace {

// The streaming decoder, fed frame by frame, gives the batch result bit for bit
// on a real-looking capture (both axes, noise, shadows, occlusions).
TEST(DecodeSimStreaming, BitIdenticalToBatch) {
    fpp::sim::Rig rig = fpp::sim::Rig::paper().without_effects();
    if (fpp::test::kSimulatedCaptureBinning > 1)
        rig = rig.binned_camera(fpp::test::kSimulatedCaptureBinning);
    rig.sensor.read_noise_dn = 1.5;
    const fpp::sim::SimulatedCapture sim =
        fpp::sim::simulate(rig, fpp::sim::named_scene("composite"),
                           fpp::standard_sequence("gray-xy", rig.projector_size), 5);
    const fpp::CaptureSet set{{}, sim.manifest, sim.frames};
    const fpp::DecodeResult batch = fpp::decode(set);
    fpp::StreamingDecoder decoder(set.manifest.sequence, set.manifest.camera,
                                  set.manifest.projector);
    for (const auto& f : set.frames)
        decoder.push(f);
    const fpp::DecodeResult streamed = decoder.finish();
    auto same = [](const auto& a, const auto& b) {
        using T = std::remove_cvref_t<decltype(*a.data())>;
        if (a.size() != b.size())
            return false;
        if (a.empty())
            return b.empty(); // memcmp must not see null pointers
        return std::memcmp(a.data(), b.data(), a.pixel_count() * sizeof(T)) == 0;
    };
    EXPECT_TRUE(same(batch.proj_x, streamed.proj_x));
    EXPECT_TRUE(same(batch.proj_y, streamed.proj_y));
    EXPECT_TRUE(same(batch.modulation, streamed.modulation));
    EXPECT_TRUE(same(batch.mean, streamed.mean));
    EXPECT_TRUE(same(batch.mask, streamed.mask));
    // Decoding into a recycled result gives the same bytes.
    fpp::DecodeResult recycled = fpp::decode(set);
    fpp::decode(set, recycled);
    EXPECT_TRUE(same(batch.proj_x, recycled.proj_x));
    EXPECT_TRUE(same(batch.mask, recycled.mask));
}

} // namespace
