// ReconnectingCamera: a camera lost with a DeviceError is closed and opened
// again at the next request, with the exposure set before the loss; another
// camera at another size is refused; a refused setting is not a loss. The
// camera here is a stand-in at the hardware boundary (the GigE camera's own
// loss and return: ScannerGige.CameraLost*).
#include "fpp/scanner/reconnecting_camera.hpp"

#include "fpp/drivers/device_error.hpp"
#include "fpp/error.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

using namespace fpp;
using namespace fpp::scanner;

namespace {

// What the stand-in cameras did, shared by every one the opener makes.
struct Bench {
    bool away = false; // opening fails (DeviceError) and the open camera's requests too
    Size size{8, 6};   // of the next camera opened
    int opened = 0;
    std::vector<double> exposures; // set_exposure_us calls, in order, on any camera
    int frames = 0;
};

class StandInCamera final : public drivers::Camera {
public:
    StandInCamera(Bench& bench, Size size) : bench_(bench), size_(size) {}
    Size size() const override { return size_; }
    int bit_depth() const override { return 8; }
    void start() override { check(); }
    void stop() override {}
    drivers::ExposureRange exposure_range_us() const override { return {10, 1000}; }
    void set_exposure_us(double exposure_us) override {
        if (!exposure_range_us().contains(exposure_us))
            throw InputError("camera settings", "exposure_us", "out of range");
        check();
        bench_.exposures.push_back(exposure_us);
    }
    void software_trigger() override { check(); }
    drivers::CapturedFrame next_frame(std::chrono::milliseconds) override {
        check();
        drivers::CapturedFrame f;
        f.frame.u8 = Image<std::uint8_t>(size_);
        f.frame_id = static_cast<std::uint64_t>(++bench_.frames);
        return f;
    }
    std::size_t frames_waiting() const override { return 0; }

private:
    void check() const {
        if (bench_.away)
            throw drivers::DeviceError(drivers::DeviceKind::camera, "camera stand-in", "no answer");
    }
    Bench& bench_;
    Size size_;
};

struct Fixture {
    Bench bench;
    std::vector<std::string> log;
    std::unique_ptr<ReconnectingCamera> camera;
    Fixture() {
        CameraOpener open = [this]() -> std::unique_ptr<drivers::Camera> {
            if (bench.away)
                throw drivers::DeviceError(drivers::DeviceKind::camera, "camera stand-in",
                                           "cannot open");
            ++bench.opened;
            return std::make_unique<StandInCamera>(bench, bench.size);
        };
        auto first = open();
        camera = std::make_unique<ReconnectingCamera>(
            std::move(open), std::move(first), "camera stand-in",
            Logger([this](LogLevel, const std::string& m) { log.push_back(m); }));
    }
};

} // namespace

TEST(ReconnectingCamera, LostCameraIsOpenedAgainWithItsExposure) {
    Fixture f;
    f.camera->set_exposure_us(250);
    f.camera->start();
    EXPECT_EQ(f.camera->next_frame(std::chrono::milliseconds(10)).frame_id, 1u);
    f.bench.away = true;
    EXPECT_THROW(f.camera->next_frame(std::chrono::milliseconds(10)), drivers::DeviceError);
    EXPECT_FALSE(f.camera->connected());
    EXPECT_EQ(f.camera->losses(), 1);
    f.camera->stop(); // closed already: nothing to do, no error
    // Still away: the request fails with the opener's error, no loss counted twice.
    EXPECT_THROW(f.camera->start(), drivers::DeviceError);
    EXPECT_EQ(f.camera->losses(), 1);
    EXPECT_EQ(f.bench.opened, 1);

    f.bench.away = false;
    f.camera->start();
    EXPECT_TRUE(f.camera->connected());
    EXPECT_EQ(f.camera->reconnections(), 1);
    EXPECT_EQ(f.bench.opened, 2);
    // The exposure set before the loss was put back on the new camera.
    EXPECT_EQ(f.bench.exposures, (std::vector<double>{250, 250}));
    EXPECT_EQ(f.camera->next_frame(std::chrono::milliseconds(10)).frame_id, 2u);
    ASSERT_EQ(f.log.size(), 2u);
    EXPECT_NE(f.log[0].find("camera stand-in closed after an error (camera stand-in: no answer)"),
              std::string::npos)
        << f.log[0];
    EXPECT_NE(f.log[1].find("camera stand-in answers again (reconnection 1)"), std::string::npos)
        << f.log[1];
}

TEST(ReconnectingCamera, RefusedSettingIsNotALoss) {
    Fixture f;
    EXPECT_THROW(f.camera->set_exposure_us(5), InputError);
    EXPECT_TRUE(f.camera->connected());
    EXPECT_EQ(f.camera->losses(), 0);
    EXPECT_TRUE(f.bench.exposures.empty());
}

TEST(ReconnectingCamera, CameraBackAtAnotherSizeIsRefused) {
    Fixture f;
    f.bench.away = true;
    EXPECT_THROW(f.camera->software_trigger(), drivers::DeviceError);
    f.bench.away = false;
    f.bench.size = Size{16, 12};
    try {
        f.camera->start();
        FAIL() << "a camera of another size was taken";
    } catch (const drivers::DeviceError& e) {
        EXPECT_NE(std::string(e.what()).find("came back as 16x12 8-bit, was 8x6 8-bit"),
                  std::string::npos)
            << e.what();
    }
    EXPECT_FALSE(f.camera->connected());
    EXPECT_EQ(f.camera->size(), (Size{8, 6}));
    f.bench.size = Size{8, 6};
    f.camera->start();
    EXPECT_EQ(f.camera->reconnections(), 1);
}
