// The virtual scanner's camera: its exposure range (reported and enforced,
// the refusal naming the range) and the exposure scaling the image.

#include "fpp/drivers/device_error.hpp"
#include "fpp/error.hpp"
#include "fpp/sim/sim_camera.hpp"
#include "fpp/sim/sim_clock.hpp"
#include "fpp/sim/sim_display.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace {

using fpp::drivers::CameraSettings;
using fpp::drivers::ExposureRange;
using fpp::drivers::TriggerMode;
using namespace fpp::sim;
using namespace std::chrono_literals;

struct Bench {
    Rig rig = Rig::paper().without_effects().binned_camera(8); // 200 x 150
    Renderer renderer{rig, named_scene("plane"), 1};
    VirtualClock clock;
    SimDisplay display{rig.projector_size, clock};
    CameraSettings settings() const {
        CameraSettings s;
        s.trigger = TriggerMode::software;
        s.exposure_us = 8000;
        return s;
    }
};

// The field and message of the InputError `f` throws, or "" when it throws none.
template <class F> std::string refusal(F f, std::string* field = nullptr) {
    try {
        f();
    } catch (const fpp::InputError& e) {
        if (field)
            *field = e.field();
        return e.what();
    }
    return "";
}

TEST(SimCamera, ReportsItsExposureRangeAndRefusesTimesOutsideItNamingTheRange) {
    Bench b;
    SimCamera camera(b.renderer, b.display, b.clock, b.settings());
    const ExposureRange range = camera.exposure_range_us();
    std::printf("sim camera exposure range %g..%g us\n", range.min_us, range.max_us);
    EXPECT_EQ(range.min_us, 10.0);
    EXPECT_EQ(range.max_us, 1e6);
    EXPECT_NO_THROW(camera.set_exposure_us(10.0));
    EXPECT_NO_THROW(camera.set_exposure_us(1e6));
    for (const double bad : {9.99, 0.0, -5.0, 1000000.5, 5e6}) {
        std::string field;
        const std::string what = refusal([&] { camera.set_exposure_us(bad); }, &field);
        EXPECT_EQ(field, "exposure_us") << bad;
        EXPECT_NE(what.find("10..1000000 us"), std::string::npos) << what;
    }
    // Another sensor's range.
    camera.set_exposure_range_us({100.0, 20000.0});
    EXPECT_EQ(camera.exposure_range_us().max_us, 20000.0);
    const std::string what = refusal([&] { camera.set_exposure_us(50.0); });
    EXPECT_NE(what.find("50 us is outside the camera's exposure range 100..20000 us"),
              std::string::npos)
        << what;
    EXPECT_NO_THROW(camera.set_exposure_us(20000.0));
    EXPECT_THROW(camera.set_exposure_range_us({0.0, 10.0}), std::invalid_argument);
    EXPECT_THROW(camera.set_exposure_range_us({20.0, 10.0}), std::invalid_argument);
    // In range but while streaming: the camera refuses (DeviceError), as before.
    camera.start();
    EXPECT_THROW(camera.set_exposure_us(1000.0), fpp::drivers::DeviceError);
    camera.stop();
}

TEST(SimCamera, ExposureScalesTheImageFromTheNominalOne) {
    Bench b;
    SimCamera camera(b.renderer, b.display, b.clock, b.settings());
    b.display.prepare({fpp::Image<std::uint8_t>(b.rig.projector_size, 1, 255)});
    b.display.show(0);
    b.display.wait_flip(100ms);
    auto centre_dn = [&](double exposure_us) {
        camera.set_exposure_us(exposure_us);
        camera.start();
        camera.software_trigger();
        const auto frame = camera.next_frame(100ms);
        camera.stop();
        return int(frame.frame.u8.at(100, 75));
    };
    const int nominal = centre_dn(8000), eighth = centre_dn(1000);
    std::printf("plane centre: %d DN at 8000 us, %d DN at 1000 us\n", nominal, eighth);
    EXPECT_NEAR(nominal, 200, 8);
    EXPECT_NEAR(eighth, nominal / 8.0, 1.0);
}

} // namespace
