// The Aravis camera driver against Aravis's own GigE Vision fake camera on
// loopback, its frames filled with fringe images rendered by the virtual
// scanner and triggered from software (the fake camera has no line trigger).
//
// Each test process moves into a network namespace of its own when it may
// (root), so that the fake cameras of tests run in parallel do not share the
// GVCP port; otherwise the processes take turns through a lock file.

#include "test_support.hpp"

#include <gtest/gtest.h>

#if __has_include(<fpp/drivers/aravis_camera.hpp>)

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/drivers/aravis_camera.hpp"
#include "fpp/drivers/aravis_fake_camera.hpp"
#include "fpp/drivers/device_error.hpp"
#include "fpp/drivers/gige_frame_ids.hpp"
#include "fpp/error.hpp"
#include "fpp/patterns.hpp"
#include "fpp/sequences.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"
#include "network_isolation.hpp"

#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace {

using fpp::drivers::AravisCamera;
using fpp::drivers::AravisFakeCamera;
using fpp::drivers::CameraSettings;
using fpp::drivers::DeviceError;
using fpp::drivers::TriggerMode;
using namespace std::chrono_literals;

// Before main(), while the process has one thread.
const fpp::test::NetworkIsolation isolation;

constexpr const char* kAddress = "127.0.0.1";

// The paper's rig, 4 x 4 binned: 400 x 300 camera, 1280 x 800 projector.
fpp::sim::Rig test_rig(int bit_depth = 8) {
    fpp::sim::Rig rig = fpp::sim::Rig::paper().without_effects().binned_camera(4);
    rig.sensor.bit_depth = bit_depth;
    if (bit_depth > 8)
        rig.sensor.white_level *= double(1 << (bit_depth - 8));
    rig.sensor.read_noise_dn = 0.5 * double(1 << (bit_depth - 8));
    return rig;
}

CameraSettings software_triggered(const std::string& pixel_format = "Mono8") {
    CameraSettings settings;
    settings.pixel_format = pixel_format;
    settings.trigger = TriggerMode::software;
    settings.exposure_us = 5000.0;
    return settings;
}

bool same_pixels(const fpp::Frame& a, const fpp::Frame& b) {
    if (a.bit_depth != b.bit_depth || a.size() != b.size())
        return false;
    return a.bit_depth == 8 ? a.u8.storage() == b.u8.storage() : a.u16.storage() == b.u16.storage();
}

// Sends `frame` through the fake camera and returns what the driver delivers.
fpp::drivers::CapturedFrame capture(AravisFakeCamera& fake, AravisCamera& camera,
                                    const fpp::Frame& frame) {
    fake.set_image(frame);
    camera.software_trigger();
    return camera.next_frame(2000ms);
}

// Images equal where both are numbers, NaN at the same pixels.
std::size_t differing_pixels(const fpp::Image<float>& a, const fpp::Image<float>& b) {
    if (a.size() != b.size())
        return std::size_t(-1);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.storage().size(); ++i) {
        const float x = a.storage()[i], y = b.storage()[i];
        const bool same = (std::isnan(x) && std::isnan(y)) || std::memcmp(&x, &y, sizeof x) == 0;
        differ += same ? 0 : 1;
    }
    return differ;
}

TEST(AravisCamera, RejectsSettingsOutOfRange) {
    CameraSettings settings = software_triggered("RGB8");
    EXPECT_THROW(AravisCamera(kAddress, settings), fpp::InputError);
    settings = software_triggered();
    settings.buffer_count = 1;
    try {
        AravisCamera camera(kAddress, settings);
        FAIL() << "one buffer accepted";
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), "buffer_count");
    }
}

TEST(AravisCamera, NoCameraAtTheAddressIsAClearDeviceError) {
    try {
        AravisCamera camera(kAddress, software_triggered());
        FAIL() << "opened a camera where there is none";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.device(), "camera 127.0.0.1");
        EXPECT_EQ(e.kind(), fpp::drivers::DeviceKind::camera);
        EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
    }
}

TEST(AravisCamera, OpensByAddressWithTheFakeCamerasRegion) {
    AravisFakeCamera fake({320, 200}, kAddress);
    {
        AravisCamera camera(kAddress, software_triggered("Mono16"));
        EXPECT_EQ(camera.size(), (fpp::Size{320, 200}));
        EXPECT_EQ(camera.bit_depth(), 16);
    }
    // A format the fake camera lacks is named in the error.
    try {
        AravisCamera mono12(kAddress, software_triggered("Mono12"));
        FAIL() << "Mono12 accepted by a camera without it";
    } catch (const DeviceError& e) {
        EXPECT_NE(std::string(e.what()).find("cannot set PixelFormat = Mono12"), std::string::npos)
            << e.what();
    }
}

// The range comes from the camera's ExposureTime bounds (the fake camera's
// GenICam file: 10 us .. 10 s); times outside it are refused naming it, at
// opening and later, before anything is sent to the camera.
TEST(AravisCamera, ReportsTheCamerasExposureRangeAndRefusesTimesOutsideIt) {
    AravisFakeCamera fake({64, 48}, kAddress);
    // At opening (one controller at a time: before the camera below opens).
    CameraSettings too_long = software_triggered();
    too_long.exposure_us = 2e7;
    try {
        AravisCamera refused(kAddress, too_long);
        ADD_FAILURE() << "an exposure beyond the camera's range was accepted at opening";
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), "exposure_us");
        EXPECT_NE(std::string(e.what()).find("exposure range 10..10000000 us"), std::string::npos)
            << e.what();
    }
    AravisCamera camera(kAddress, software_triggered());
    const fpp::drivers::ExposureRange range = camera.exposure_range_us();
    std::cout << "[ figures  ] fake camera exposure range " << range.min_us << ".." << range.max_us
              << " us\n";
    EXPECT_GT(range.min_us, 0.0);
    EXPECT_LE(range.min_us, 100.0);
    EXPECT_GE(range.max_us, 1e6);
    EXPECT_LE(range.max_us, 1e8);
    EXPECT_TRUE(range.contains(5000.0)); // the settings' exposure
    EXPECT_NO_THROW(camera.set_exposure_us(range.min_us));
    EXPECT_NO_THROW(camera.set_exposure_us(range.max_us));
    EXPECT_NO_THROW(camera.set_exposure_us(5000.0));
    for (const double bad : {range.min_us / 2, range.max_us * 2, 0.0}) {
        try {
            camera.set_exposure_us(bad);
            ADD_FAILURE() << bad << " us accepted";
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.field(), "exposure_us");
            EXPECT_NE(std::string(e.what()).find("exposure range"), std::string::npos) << e.what();
        }
    }
    // The camera still delivers frames after the refusals.
    fpp::Frame frame;
    frame.u8 = fpp::Image<std::uint8_t>({64, 48}, 1, 77);
    camera.start();
    EXPECT_TRUE(same_pixels(capture(fake, camera, frame).frame, frame));
    camera.stop();
}

TEST(AravisCamera, DeliversRenderedFramesInOrderPixelForPixel) {
    for (const int bit_depth : {8, 16}) {
        SCOPED_TRACE(bit_depth);
        const fpp::sim::Rig rig = test_rig(bit_depth == 8 ? 8 : 12);
        const fpp::sim::Renderer renderer(rig, fpp::sim::named_scene("composite"), 1);
        const fpp::Sequence sequence = fpp::standard_sequence("gray-x", rig.projector_size);
        const auto patterns = fpp::render_sequence(sequence, rig.projector_size);

        AravisFakeCamera fake(rig.camera_size, kAddress);
        AravisCamera camera(kAddress, software_triggered(bit_depth == 8 ? "Mono8" : "Mono16"));
        ASSERT_EQ(camera.size(), rig.camera_size);
        camera.start();
        std::uint64_t previous_id = 0;
        std::int64_t previous_ns = 0;
        for (int k = 0; k < 6; ++k) {
            const fpp::Frame rendered =
                renderer.render(patterns[std::size_t(k)], std::uint64_t(k + 1));
            const auto got = capture(fake, camera, rendered);
            EXPECT_TRUE(same_pixels(got.frame, rendered)) << "frame " << k;
            if (k > 0) {
                EXPECT_EQ(got.frame_id, fpp::drivers::gige_next_frame_id(previous_id));
                EXPECT_GT(got.timestamp_ns, previous_ns);
            }
            previous_id = got.frame_id;
            previous_ns = got.timestamp_ns;
            EXPECT_EQ(camera.buffers_outstanding(), 0);
        }
        camera.stop();
    }
}

// A whole fringe sequence through the fake camera decodes to exactly the
// projector coordinates of the frames decoded directly.
TEST(AravisCamera, FringeSequenceThroughTheCameraDecodesBitIdentically) {
    const fpp::sim::Rig rig = test_rig();
    const fpp::sim::Renderer renderer(rig, fpp::sim::named_scene("composite"));
    const fpp::Sequence sequence = fpp::standard_sequence("gray-xy", rig.projector_size);
    const fpp::sim::SimulatedCapture direct = fpp::sim::simulate(renderer, sequence, 7);

    AravisFakeCamera fake(rig.camera_size, kAddress);
    AravisCamera camera(kAddress, software_triggered());
    camera.start();
    fpp::CaptureSet through_camera;
    through_camera.manifest = direct.manifest;
    const auto t0 = std::chrono::steady_clock::now();
    std::uint64_t previous_id = 0;
    for (std::size_t k = 0; k < direct.frames.size(); ++k) {
        auto got = capture(fake, camera, direct.frames[k]);
        if (k > 0) {
            EXPECT_EQ(got.frame_id, fpp::drivers::gige_next_frame_id(previous_id));
        }
        previous_id = got.frame_id;
        through_camera.frames.push_back(std::move(got.frame));
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    camera.stop();
    std::cout << "[ figures  ] " << direct.frames.size() << " frames of " << rig.camera_size.width
              << "x" << rig.camera_size.height << " through the fake GigE camera in " << seconds
              << " s (" << double(direct.frames.size()) / seconds
              << " frames/s, trigger to frame)\n";

    fpp::CaptureSet direct_set;
    direct_set.manifest = direct.manifest;
    direct_set.frames = direct.frames;
    const fpp::DecodeResult expected = fpp::decode(direct_set);
    const fpp::DecodeResult decoded = fpp::decode(through_camera);
    std::size_t valid = 0;
    for (const std::uint8_t m : expected.mask.storage())
        valid += (m & fpp::kDecodeValid) ? 1 : 0;
    ASSERT_GT(valid, expected.mask.pixel_count() / 3) << "scene barely decodes; test is void";
    EXPECT_EQ(decoded.mask.storage(), expected.mask.storage());
    EXPECT_EQ(differing_pixels(decoded.proj_x, expected.proj_x), 0u);
    EXPECT_EQ(differing_pixels(decoded.proj_y, expected.proj_y), 0u);
    std::cout << "[ figures  ] decode through the camera: " << valid
              << " valid pixels, bit-identical to the direct decode\n";
}

// Enough frames to pass the 16-bit frame id wrap (65535 -> 1) of GVSP 1.x.
TEST(AravisCamera, SustainedStreamKeepsIdsConsecutiveAndBuffersInThePool) {
    const fpp::Size size{400, 300};
    AravisFakeCamera fake(size, kAddress);
    fpp::Frame frame;
    frame.u8 = fpp::Image<std::uint8_t>(size, 1, 0);
    AravisCamera camera(kAddress, software_triggered());
    camera.start();
    std::uint64_t previous_id = 0, first_id = 0;
    bool wrapped = false;
    const int count = 200;
    const auto t0 = std::chrono::steady_clock::now();
    for (int k = 0; k < count; ++k) {
        frame.u8.storage()[std::size_t(k)] = static_cast<std::uint8_t>(k + 1); // tags frame k
        const auto got = capture(fake, camera, frame);
        ASSERT_EQ(got.frame.u8.storage()[std::size_t(k)], k + 1) << "frame " << k << " is stale";
        if (k == 0)
            first_id = got.frame_id;
        if (k > 0) {
            ASSERT_EQ(got.frame_id, fpp::drivers::gige_next_frame_id(previous_id));
            wrapped = wrapped || got.frame_id < previous_id;
        }
        previous_id = got.frame_id;
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::cout << "[ figures  ] " << count << " frames 400x300 Mono8, ids " << first_id << ".."
              << previous_id << ", " << double(count) / seconds << " frames/s\n";
    EXPECT_EQ(camera.buffers_outstanding(), 0);
    EXPECT_EQ(fake.frames_sent(), std::uint64_t(count));
    // The fake camera starts its counter near the wrap to catch counter bugs.
    if (first_id > 65535 - count) {
        EXPECT_TRUE(wrapped);
    }
}

TEST(AravisCamera, LateFrameTimesOutWithADeviceErrorNamingIt) {
    AravisFakeCamera fake({64, 48}, kAddress);
    CameraSettings settings = software_triggered();
    settings.trigger = TriggerMode::line; // the fake camera has no line trigger: no frame comes
    settings.trigger_source = "Line0";
    AravisCamera camera(kAddress, settings);
    EXPECT_THROW(camera.software_trigger(), DeviceError);
    camera.start();
    try {
        (void)camera.next_frame(150ms);
        FAIL() << "a frame without a trigger";
    } catch (const DeviceError& e) {
        EXPECT_NE(std::string(e.what()).find("first frame did not arrive within 150 ms"),
                  std::string::npos)
            << e.what();
    }
    EXPECT_EQ(camera.buffers_outstanding(), 0);
}

TEST(AravisCamera, CameraGoneMidStreamIsADeviceError) {
    auto fake = std::make_unique<AravisFakeCamera>(fpp::Size{64, 48}, kAddress);
    AravisCamera camera(kAddress, software_triggered());
    camera.start();
    fpp::Frame frame;
    frame.u8 = fpp::Image<std::uint8_t>(64, 48, 1, 9);
    const auto first = capture(*fake, camera, frame);
    EXPECT_EQ(first.frame.u8.at(5, 5), 9);
    fake.reset(); // the camera vanishes

    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_THROW(camera.software_trigger(), DeviceError);
    try {
        (void)camera.next_frame(200ms);
        FAIL() << "a frame from a camera that is gone";
    } catch (const DeviceError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("frame " +
                            std::to_string(fpp::drivers::gige_next_frame_id(first.frame_id)) +
                            " did not arrive within 200 ms"),
                  std::string::npos)
            << what;
    }
    // One control command's retries (5 x 0.5 s in Aravis 0.8) plus the frame timeout.
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 4s);
    EXPECT_EQ(camera.buffers_outstanding(), 0);
    camera.stop(); // does not wait on a camera known to be gone
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 4s);
    // The camera comes back (power cycle) before the driver is closed: closing
    // it then takes no retries (against a vanished camera Aravis spends about
    // 7.5 s in retries while closing the stream and releasing control).
    fake = std::make_unique<AravisFakeCamera>(fpp::Size{64, 48}, kAddress);
}

} // namespace

#else

TEST(AravisCamera, NotBuilt) {
    if (fpp::test::in_ci())
        FAIL() << "fpp_aravis is not linked to this test";
    GTEST_SKIP() << "the Aravis driver is not built (aravis-0.8 not found)";
}

#endif
