// The scanner with its camera reached over GigE Vision: the virtual scanner
// renders each frame into Aravis's fake GigE camera on loopback and the
// scanner's Aravis driver receives it over UDP (a sim board with
// camera.driver aravis). Also a hardware board on a machine without the
// hardware: a clear error naming the device, no output.
#include "test_support.hpp"

#include <gtest/gtest.h>

#if __has_include(<fpp/drivers/aravis_camera.hpp>)

#include "fpp/error.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/scanner/board_config.hpp"
#include "fpp/scanner/camera_wait.hpp"
#include "fpp/scanner/scan_store.hpp"
#include "fpp/scanner/scanner.hpp"
#include "fpp/scanner/sim_board.hpp"
#include "network_isolation.hpp"
#include "rig_truth_table.hpp"
#include "sim_board_yaml.hpp"

#include <fpp/drivers/aravis_camera.hpp>
#include <fpp/drivers/aravis_fake_camera.hpp>
#include <fpp/drivers/device_error.hpp>
#include <fpp/sim/sim_gpio.hpp>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace fs = std::filesystem;
using namespace fpp;
using namespace fpp::scanner;

namespace {

// Before main(), while the process has one thread.
const fpp::test::NetworkIsolation isolation;

// The test board with its camera behind the GigE link (steady clock, 5 ms flips).
std::string gige_board_yaml(const fs::path& store) {
    fpp::test::SimBoardYaml b;
    b.name = "test-sim-gige";
    b.store = store;
    b.table = "table.fpt";
    b.gige = true;
    b.steady_clock = true;
    b.flip_latency_us = 5000;
    b.frame_timeout_ms = 1000;
    return b.text();
}

struct GigeFixture {
    fpp::test::TempDir dir;
    fs::path board_file = dir / "board.yaml";
    fs::path store = dir / "scans";
    BoardConfig board;
    GigeFixture() {
        std::ofstream(board_file) << gige_board_yaml(store);
        board = read_board_config(board_file);
    }
};

} // namespace

TEST(ScannerGige, BoardNeedsSoftwareTriggerSteadyClockAndAnAddress) {
    GigeFixture f;
    EXPECT_EQ(f.board.camera.driver, CameraDriver::aravis);
    ASSERT_TRUE(f.board.sim.has_value());
    const std::string text = gige_board_yaml(f.store);
    auto expect_field = [&](const std::string& from, const std::string& to,
                            const std::string& field) {
        std::string bad = text;
        bad.replace(bad.find(from), from.size(), to);
        try {
            parse_board_config(bad, f.board_file);
            ADD_FAILURE() << "accepted: " << to;
        } catch (const InputError& e) {
            EXPECT_EQ(e.field(), field) << e.what();
        }
    };
    expect_field("trigger: software", "trigger: line", "camera.trigger");
    expect_field("device: 127.0.0.1", "device: \"\"", "camera.device");
    expect_field("clock: steady", "clock: virtual", "sim.clock");
}

TEST(ScannerGige, ScanThroughTheFakeGigeCameraIsCloseToTruth) {
    GigeFixture f;
    SimBoard sim(f.board);
    write_table(f.dir / "table.fpt", fpp::test::rig_truth_table(sim.rig()));
    const Logger log{[](LogLevel, const std::string&) {}};
    Scanner scanner(f.board, sim.devices(), log);
    const ScanOutcome out = scanner.scan(ScanMode::scan);

    EXPECT_EQ(out.attempts, 1);
    EXPECT_EQ(out.frames, scanner.frames_per_scan());
    EXPECT_GT(out.points, 60000u);
    std::size_t compared = 0;
    const double rms = fpp::test::ply_rms_against_truth(out.folder / "cloud.ply",
                                                        sim.renderer().truth_xyz(), compared);
    std::printf("GigE scan: %zu points, RMS %.4f mm against truth over %zu; capture %.1f ms\n",
                out.points, rms, compared, out.timings.capture_ms);
    EXPECT_GT(compared, out.points * 9 / 10);
    EXPECT_LT(rms, 0.1);
    // Each frame that crossed the link was exposed under its own pattern.
    const auto& exposures = sim.camera().exposures();
    ASSERT_EQ(exposures.size(), static_cast<std::size_t>(out.frames));
    for (std::size_t i = 0; i < exposures.size(); ++i) {
        EXPECT_EQ(exposures[i].pattern, static_cast<int>(i));
        EXPECT_EQ(exposures[i].pattern_at_end, static_cast<int>(i));
    }

    // A second scan through the same stream (buffers went back to it); the
    // sensor noise differs, so a few edge pixels may too.
    const ScanOutcome again = scanner.scan(ScanMode::scan);
    EXPECT_EQ(again.attempts, 1);
    EXPECT_NEAR(static_cast<double>(again.points), static_cast<double>(out.points),
                0.001 * static_cast<double>(out.points));
}

#ifdef FPP_SCANNER_EXE
TEST(ScannerGige, ScannerBinaryScansThroughTheLink) {
    GigeFixture f;
    {
        SimBoard sim(f.board); // the rig as the board binns it (no camera is opened yet: the
                               // fake camera of this scope is gone before the binary starts)
        write_table(f.dir / "table.fpt", fpp::test::rig_truth_table(sim.rig()));
    }
    fpp::test::TempDir scratch;
    const auto run = fpp::test::run_tool(
        FPP_SCANNER_EXE, "--board " + fpp::test::shell_quote(f.board_file) + " --once",
        scratch.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const auto scans = list_scans(f.store);
    ASSERT_EQ(scans.size(), 1u);
    EXPECT_TRUE(fs::exists(scans[0] / "cloud.ply"));
    EXPECT_NE(run.output.find(scans[0].string()), std::string::npos) << run.output;
}

// What a scanner service logs while it waits for its camera.
struct LogLines {
    std::vector<std::pair<LogLevel, std::string>> lines;
    Logger logger() {
        return Logger(
            [this](LogLevel level, const std::string& m) { lines.emplace_back(level, m); });
    }
    int count(LogLevel level) const {
        int n = 0;
        for (const auto& line : lines)
            n += line.first == level ? 1 : 0;
        return n;
    }
};

TEST(ScannerGige, ServiceWaitsForACameraThatDoesNotAnswerYet) {
    // Nothing answers at 127.0.0.1 at the first attempt (the real Aravis
    // driver looks for it); the fake camera starts before the second, as a
    // GigE camera still booting when the service starts.
    GigeFixture f;
    std::optional<drivers::AravisFakeCamera> fake;
    int attempts = 0;
    const CameraOpener open = [&]() -> std::unique_ptr<drivers::Camera> {
        if (++attempts == 2)
            fake.emplace(Size{64, 48}, f.board.camera.device);
        return std::make_unique<drivers::AravisCamera>(f.board.camera.device,
                                                       f.board.camera.settings);
    };
    sim::SimLed led;
    LogLines log;
    const std::atomic<bool> stop{false};
    CameraWaitOptions options;
    options.retry = std::chrono::milliseconds(100);
    const CameraWaitResult result = wait_for_camera(open, led, log.logger(), stop, options);
    ASSERT_NE(result.camera, nullptr);
    EXPECT_EQ(result.camera->size(), (Size{64, 48}));
    EXPECT_EQ(result.failed_attempts, 1);
    EXPECT_EQ(attempts, 2);
    EXPECT_EQ(led.history(),
              (std::vector<drivers::LedState>{drivers::LedState::off, drivers::LedState::error}));
    ASSERT_EQ(log.count(LogLevel::error), 1);
    EXPECT_NE(log.lines[0].second.find("camera 127.0.0.1"), std::string::npos)
        << log.lines[0].second;
    EXPECT_NE(log.lines[0].second.find("waiting for it"), std::string::npos) << log.lines[0].second;
    ASSERT_EQ(log.count(LogLevel::info), 1);
    EXPECT_NE(log.lines[1].second.find("answered after 1 failed attempt"), std::string::npos)
        << log.lines[1].second;
}

TEST(ScannerGige, StopWhileWaitingForTheCameraReturnsNoCamera) {
    // A SIGTERM while no camera answers: the wait ends after the attempt in
    // progress, with no camera and the LED still showing the error.
    GigeFixture f;
    int attempts = 0;
    const CameraOpener open = [&]() -> std::unique_ptr<drivers::Camera> {
        ++attempts;
        return std::make_unique<drivers::AravisCamera>(f.board.camera.device,
                                                       f.board.camera.settings);
    };
    sim::SimLed led;
    std::atomic<bool> stop{false};
    const Logger log([&](LogLevel, const std::string&) { stop.store(true); });
    CameraWaitOptions options;
    options.retry = std::chrono::hours(1); // only the stop request can end the pause
    options.reminder = options.retry;
    const CameraWaitResult result = wait_for_camera(open, led, log, stop, options);
    EXPECT_EQ(result.camera, nullptr);
    EXPECT_EQ(result.failed_attempts, 1);
    EXPECT_EQ(attempts, 1);
    EXPECT_EQ(led.state(), drivers::LedState::error);

    options.retry = std::chrono::milliseconds(0);
    EXPECT_THROW(wait_for_camera(open, led, log, stop, options), std::invalid_argument);
    options.retry = std::chrono::milliseconds(100);
    options.reminder = std::chrono::milliseconds(10);
    EXPECT_THROW(wait_for_camera(open, led, log, stop, options), std::invalid_argument);
}

TEST(ScannerGige, HardwareBoardWithoutTheHardwareFailsNamingTheDevice) {
    // The same board without its sim section: DRM display, GPIO lines, Aravis
    // camera. This machine has no /dev/dri card (or no free one), no such
    // GPIO chip and no camera: the first device opened is named, nothing is
    // written.
    fpp::test::TempDir dir;
    std::string text = gige_board_yaml(dir / "scans");
    text = text.substr(0, text.find("sim: {"));
    text.replace(text.find("card: auto"), 10, "card: /dev/dri/card9");
    const fs::path board = dir / "hardware.yaml";
    std::ofstream(board) << text;
    fpp::test::TempDir scratch;
    const auto run = fpp::test::run_tool(
        FPP_SCANNER_EXE, "--board " + fpp::test::shell_quote(board) + " --once --mode capture",
        scratch.path());
    EXPECT_EQ(run.exit_code, 1) << run.output;
    const bool named = run.output.find("gpiochip0") != std::string::npos ||
                       run.output.find("/dev/dri/card9") != std::string::npos;
    EXPECT_TRUE(named) << run.output;
    EXPECT_NE(run.output.find("error"), std::string::npos) << run.output;
    EXPECT_FALSE(fs::exists(dir / "scans") && !fs::is_empty(dir / "scans"));

    // The same with only the camera simulated (sim.camera_only): the display
    // and the lines are still this machine's, which it lacks.
    std::string camera_only = gige_board_yaml(dir / "scans");
    camera_only.replace(camera_only.find("seed: 3}"), 8, "seed: 3, camera_only: true}");
    const fs::path board2 = dir / "camera-only.yaml";
    std::ofstream(board2) << camera_only;
    const auto run2 = fpp::test::run_tool(
        FPP_SCANNER_EXE, "--board " + fpp::test::shell_quote(board2) + " --once --mode capture",
        scratch.path());
    EXPECT_EQ(run2.exit_code, 1) << run2.output;
    EXPECT_NE(run2.output.find("error: gpiochip0"), std::string::npos) << run2.output;
    EXPECT_FALSE(fs::exists(dir / "scans") && !fs::is_empty(dir / "scans"));
}
#endif

#else

TEST(ScannerGige, NotBuilt) {
    if (fpp::test::in_ci())
        FAIL() << "fpp_aravis is not linked to this test";
    GTEST_SKIP() << "the Aravis driver is not built (aravis-0.8 not found)";
}

#endif
