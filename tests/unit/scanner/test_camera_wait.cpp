// Waiting for a camera that does not answer yet (fpp/scanner/camera_wait.hpp):
// attempts until it answers, the LED in its error state meanwhile, the error
// logged at the first attempt and then at most every reminder, a stop request
// ending the wait, other errors passed on, and the options' refusals. The
// camera is a stand-in (the real GigE camera's wait: ScannerGige.Service*).

#include "fpp/scanner/camera_wait.hpp"

#include "fpp/drivers/device_error.hpp"
#include "fpp/error.hpp"
#include "fpp/sim/sim_gpio.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

using namespace fpp;
using namespace fpp::scanner;
using namespace std::chrono_literals;

namespace {

class StandInCamera final : public drivers::Camera {
public:
    Size size() const override { return {8, 6}; }
    int bit_depth() const override { return 8; }
    void start() override {}
    void stop() override {}
    drivers::ExposureRange exposure_range_us() const override { return {10, 1000}; }
    void set_exposure_us(double) override {}
    void software_trigger() override {}
    drivers::CapturedFrame next_frame(std::chrono::milliseconds) override {
        throw drivers::DeviceError(drivers::DeviceKind::camera, "stand-in", "no frames");
    }
    std::size_t frames_waiting() const override { return 0; }
};

// An opener whose first `failures` attempts find no camera.
struct Opener {
    int failures = 0;
    int attempts = 0;
    CameraOpener function() {
        return [this]() -> std::unique_ptr<drivers::Camera> {
            if (++attempts <= failures)
                throw drivers::DeviceError(drivers::DeviceKind::camera, "camera 10.0.0.7",
                                           "no answer to the discovery");
            return std::make_unique<StandInCamera>();
        };
    }
};

struct Lines {
    std::vector<std::pair<LogLevel, std::string>> lines;
    Logger logger() {
        return Logger(
            [this](LogLevel level, const std::string& m) { lines.emplace_back(level, m); });
    }
};

CameraWaitOptions fast(std::chrono::milliseconds reminder = 1h) {
    CameraWaitOptions options;
    options.retry = 1ms;
    options.reminder = reminder;
    return options;
}

const std::string kNoAnswer = "camera 10.0.0.7: no answer to the discovery; waiting for it";

TEST(CameraWait, ACameraThatAnswersAtOnceIsOpenedWithoutAWord) {
    Opener opener;
    sim::SimLed led;
    Lines log;
    const std::atomic<bool> stop{false};
    const CameraWaitResult result = wait_for_camera(opener.function(), led, log.logger(), stop);
    ASSERT_NE(result.camera, nullptr);
    EXPECT_EQ(result.camera->size(), (Size{8, 6}));
    EXPECT_EQ(result.failed_attempts, 0);
    EXPECT_EQ(opener.attempts, 1);
    EXPECT_EQ(led.history(), std::vector<drivers::LedState>{drivers::LedState::off});
    EXPECT_TRUE(log.lines.empty());
}

TEST(CameraWait, WaitsWithTheLedInErrorAndLogsTheFirstFailureAndTheAnswer) {
    Opener opener{3};
    sim::SimLed led;
    Lines log;
    const std::atomic<bool> stop{false};
    const CameraWaitResult result =
        wait_for_camera(opener.function(), led, log.logger(), stop, fast());
    ASSERT_NE(result.camera, nullptr);
    EXPECT_EQ(result.failed_attempts, 3);
    EXPECT_EQ(opener.attempts, 4);
    using drivers::LedState;
    EXPECT_EQ(led.history(), (std::vector<LedState>{LedState::off, LedState::error, LedState::error,
                                                    LedState::error}));
    const std::vector<std::pair<LogLevel, std::string>> expected{
        {LogLevel::error, kNoAnswer + " (attempt 1, again every 1 ms)"},
        {LogLevel::info, "camera answered after 3 failed attempt(s)"}};
    EXPECT_EQ(log.lines, expected);
}

TEST(CameraWait, TheErrorIsRepeatedOncePerReminderWithTheAttemptsSoFar) {
    // Each retry waits at least the reminder's length: every attempt reminds.
    Opener opener{3};
    sim::SimLed led;
    Lines log;
    const std::atomic<bool> stop{false};
    const CameraWaitResult result =
        wait_for_camera(opener.function(), led, log.logger(), stop, fast(1ms));
    ASSERT_NE(result.camera, nullptr);
    const std::vector<std::pair<LogLevel, std::string>> expected{
        {LogLevel::error, kNoAnswer + " (attempt 1, again every 1 ms)"},
        {LogLevel::error, kNoAnswer + " (attempt 2, again every 1 ms)"},
        {LogLevel::error, kNoAnswer + " (attempt 3, again every 1 ms)"},
        {LogLevel::info, "camera answered after 3 failed attempt(s)"}};
    EXPECT_EQ(log.lines, expected);
}

TEST(CameraWait, AStopRequestBeforeTheFirstAttemptTriesNothing) {
    Opener opener;
    sim::SimLed led;
    Lines log;
    const std::atomic<bool> stop{true};
    const CameraWaitResult result = wait_for_camera(opener.function(), led, log.logger(), stop);
    EXPECT_EQ(result.camera, nullptr);
    EXPECT_EQ(result.failed_attempts, 0);
    EXPECT_EQ(opener.attempts, 0);
    EXPECT_TRUE(log.lines.empty());
}

TEST(CameraWait, AStopRequestEndsThePauseBetweenAttempts) {
    // The pause is an hour; the stop request, made as the failure is logged,
    // ends the wait after that attempt with no camera and the LED in error.
    Opener opener{1000};
    sim::SimLed led;
    std::atomic<bool> stop{false};
    int logged = 0;
    const Logger log([&](LogLevel, const std::string&) {
        ++logged;
        stop = true;
    });
    CameraWaitOptions options;
    options.retry = 1h;
    options.reminder = 1h;
    const CameraWaitResult result = wait_for_camera(opener.function(), led, log, stop, options);
    EXPECT_EQ(result.camera, nullptr);
    EXPECT_EQ(result.failed_attempts, 1);
    EXPECT_EQ(opener.attempts, 1);
    EXPECT_EQ(logged, 1);
    EXPECT_EQ(led.state(), drivers::LedState::error);
}

TEST(CameraWait, ErrorsOtherThanTheDevicesArePassedOn) {
    sim::SimLed led;
    Lines log;
    const std::atomic<bool> stop{false};
    int attempts = 0;
    const CameraOpener refused = [&]() -> std::unique_ptr<drivers::Camera> {
        ++attempts;
        throw InputError("board.yaml", "camera.pixel_format", "must be Mono8 or Mono16");
    };
    EXPECT_THROW(wait_for_camera(refused, led, log.logger(), stop, fast()), InputError);
    EXPECT_EQ(attempts, 1);
    EXPECT_EQ(led.history(), std::vector<drivers::LedState>{drivers::LedState::off});
    EXPECT_TRUE(log.lines.empty());
}

TEST(CameraWait, OptionsAreRefusedNamingTheField) {
    EXPECT_NO_THROW(CameraWaitOptions{}.validate());
    const auto message = [](const CameraWaitOptions& options) -> std::string {
        try {
            options.validate();
        } catch (const std::invalid_argument& e) {
            return e.what();
        }
        return "accepted";
    };
    CameraWaitOptions options;
    options.retry = 0ms;
    EXPECT_EQ(message(options), "CameraWaitOptions.retry must be positive");
    options.retry = -5ms;
    EXPECT_EQ(message(options), "CameraWaitOptions.retry must be positive");
    options.retry = 100ms;
    options.reminder = 99ms;
    EXPECT_EQ(message(options), "CameraWaitOptions.reminder must be at least retry");
    options.reminder = 100ms;
    EXPECT_EQ(message(options), "accepted");
    // wait_for_camera checks them before any attempt.
    Opener opener;
    sim::SimLed led;
    const std::atomic<bool> stop{false};
    options.retry = 0ms;
    EXPECT_THROW(wait_for_camera(opener.function(), led, Logger(Logger::Sink{}), stop, options),
                 std::invalid_argument);
    EXPECT_EQ(opener.attempts, 0);
}

} // namespace
