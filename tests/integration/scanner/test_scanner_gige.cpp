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
#include <cstdlib>
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

// Packet loss on the link: a share of the UDP datagrams (GVCP control and
// GVSP stream alike) dropped on the loopback interface of this test's own
// network namespace, by iptables' statistic match (this kernel has no netem
// queueing discipline, so frames cannot be made late, only lost).
struct PacketLoss {
    static bool available() {
        return isolation.namespaced &&
               std::system("iptables-legacy -L OUTPUT -n > /dev/null 2>&1") == 0;
    }
    explicit PacketLoss(double probability) {
        char command[200];
        std::snprintf(command, sizeof command,
                      "iptables-legacy -A OUTPUT -o lo -p udp -m statistic --mode random "
                      "--probability %.4f -j DROP",
                      probability);
        ok = std::system(command) == 0;
    }
    ~PacketLoss() { (void)std::system("iptables-legacy -F OUTPUT"); }
    PacketLoss(const PacketLoss&) = delete;
    PacketLoss& operator=(const PacketLoss&) = delete;
    bool ok = false;
};

TEST(ScannerGige, PacketLossRetriesOrFailsCleanlyAndNeverDecodesOnePatternAsAnother) {
    if (!PacketLoss::available()) {
        if (fpp::test::in_ci())
            FAIL() << "needs its own network namespace and iptables-legacy (package iptables)";
        GTEST_SKIP() << "needs its own network namespace and iptables-legacy";
    }
    GigeFixture f;
    const Logger log{[](LogLevel, const std::string&) {}};
    SimBoard sim(f.board, log);
    write_table(f.dir / "table.fpt", fpp::test::rig_truth_table(sim.rig()));
    Scanner scanner(f.board, sim.devices(), log);
    constexpr int kScans = 6;
    for (const double loss : {0.001, 0.01}) {
        int written = 0, retried = 0, failed = 0;
        std::string first_failure;
        {
            const PacketLoss dropping(loss);
            ASSERT_TRUE(dropping.ok);
            for (int k = 0; k < kScans; ++k) {
                const std::size_t scans_before = list_scans(f.store).size();
                try {
                    const ScanOutcome out = scanner.scan(ScanMode::scan);
                    ++written;
                    retried += out.attempts > 1 ? 1 : 0;
                    EXPECT_LE(out.attempts, 2);
                    // Every frame decoded under its own pattern: one frame
                    // of another pattern would put thousands of points far
                    // off the truth. The sensor's noise differs with the
                    // frame ids that the failed attempts used up, and one
                    // noise draw in a few hundred decodes a pixel to a wrong
                    // fringe order (one point 85 mm off, RMS 0.265 mm; the
                    // same draw on the sim board without any link does too).
                    const fpp::test::TruthErrors errors = fpp::test::ply_errors_against_truth(
                        out.folder / "cloud.ply", sim.renderer().truth_xyz(), 5.0);
                    EXPECT_LE(errors.gross, 5u) << "loss " << loss << ", scan " << k;
                    EXPECT_LT(errors.rms_without_gross_mm, 0.1)
                        << "loss " << loss << ", scan " << k;
                    EXPECT_GT(out.points, 60000u);
                } catch (const drivers::DeviceError& e) {
                    if (failed++ == 0)
                        first_failure = e.what();
                    EXPECT_NE(std::string(e.what()).find("camera"), std::string::npos) << e.what();
                    EXPECT_EQ(sim.led().state(), drivers::LedState::error);
                    EXPECT_EQ(list_scans(f.store).size(), scans_before);
                }
            }
        }
        std::printf(
            "packet loss %.1f %%: %d of %d scans written (%d after a retry), %d failed%s%s\n",
            100 * loss, written, kScans, retried, failed, failed ? ", first: " : "",
            first_failure.c_str());
    }
    // The link whole again: the next scan is written at the first attempt.
    const ScanOutcome out = scanner.scan(ScanMode::scan);
    EXPECT_EQ(out.attempts, 1);
    // Nothing but whole scans in the store.
    for (const fs::path& entry : fpp::test::entries_under(f.store))
        EXPECT_EQ(entry.string().find(".tmp"), std::string::npos) << entry;
}

TEST(ScannerGige, ScannerBinaryScansThroughTheLink) {
    GigeFixture f;
    {
        SimBoard sim(f.board); // the rig as the board binns it (no camera is opened yet: the
                               // fake camera of this scope is gone before the binary starts)
        write_table(f.dir / "table.fpt", fpp::test::rig_truth_table(sim.rig()));
    }
    fpp::test::TempDir scratch;
    const auto run = fpp::test::run_tool(
        fpp::test::scanner_exe(), "--board " + fpp::test::shell_quote(f.board_file) + " --once",
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

// Pulls the link's cable when frame `at` of a scan has arrived (on the
// scanning thread, between two frames: mid-scan).
struct UnplugAtFrame final : ScanObserver {
    SimBoard& sim;
    int at;
    bool unplugged = false;
    std::string failure;
    UnplugAtFrame(SimBoard& s, int frame) : sim(s), at(frame) {}
    void scan_started(const std::string&, ScanMode, int) override {}
    void frame_captured(int frame, int) override {
        if (!unplugged && frame == at) {
            sim.unplug_camera();
            unplugged = true;
        }
    }
    void decoded() override {}
    void written(const ScanOutcome&) override {}
    void failed(const std::string& reason) override { failure = reason; }
};

TEST(ScannerGige, CameraLostMidScanFailsCleanlyAndTheScanAfterItsReturnSucceeds) {
    // Aravis's fake camera goes away at frame 5 of a scan (the cable pulled)
    // and comes back later (a new one at the same address, as after a power
    // cycle). The same Scanner, never rebuilt, is the running service.
    GigeFixture f;
    LogLines lines;
    const Logger log = lines.logger();
    SimBoard sim(f.board, log);
    write_table(f.dir / "table.fpt", fpp::test::rig_truth_table(sim.rig()));
    Scanner scanner(f.board, sim.devices(), log);
    UnplugAtFrame observer(sim, 5);
    scanner.set_observer(&observer);

    try {
        scanner.scan(ScanMode::scan);
        FAIL() << "a scan without its camera succeeded";
    } catch (const drivers::DeviceError& e) {
        EXPECT_NE(std::string(e.what()).find("camera 127.0.0.1"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(observer.unplugged);
    EXPECT_EQ(observer.failure.rfind("camera 127.0.0.1", 0), 0u) << observer.failure;
    EXPECT_EQ(sim.led().state(), drivers::LedState::error);
    EXPECT_TRUE(fpp::test::entries_under(f.store).empty())
        << fpp::test::entries_under(f.store).front();
    // Logged: the loss (the driver closed) and the failure with its reason.
    bool closed = false;
    bool failed = false;
    for (const auto& [level, line] : lines.lines) {
        closed |= level == LogLevel::warning && line.find("camera 127.0.0.1 closed after an "
                                                          "error") != std::string::npos;
        failed |= level == LogLevel::error && line.rfind("scan failed: camera 127.0.0.1", 0) == 0;
    }
    EXPECT_TRUE(closed);
    EXPECT_TRUE(failed);

    // Still away: the next scan fails at its first camera request.
    observer.at = 0;
    EXPECT_THROW(scanner.scan(ScanMode::scan), drivers::DeviceError);
    EXPECT_EQ(sim.led().state(), drivers::LedState::error);
    EXPECT_TRUE(fpp::test::entries_under(f.store).empty());

    // Back: the next scan opens it again and is as good as before the loss.
    sim.plug_camera();
    const std::size_t exposures_before = sim.camera().exposures().size();
    const ScanOutcome out = scanner.scan(ScanMode::scan);
    EXPECT_EQ(out.attempts, 1);
    EXPECT_EQ(sim.led().state(), drivers::LedState::ready);
    EXPECT_EQ(list_scans(f.store).size(), 1u);
    std::size_t compared = 0;
    const double rms = fpp::test::ply_rms_against_truth(out.folder / "cloud.ply",
                                                        sim.renderer().truth_xyz(), compared);
    std::printf("after the camera's return: %zu points, RMS %.4f mm against truth\n", out.points,
                rms);
    EXPECT_GT(out.points, 60000u);
    EXPECT_LT(rms, 0.1);
    // Each frame of it was exposed under its own pattern.
    const auto& exposures = sim.camera().exposures();
    ASSERT_EQ(exposures.size(), exposures_before + static_cast<std::size_t>(out.frames));
    for (std::size_t i = 0; i < static_cast<std::size_t>(out.frames); ++i)
        EXPECT_EQ(exposures[exposures_before + i].pattern, static_cast<int>(i));
    bool answered = false;
    for (const auto& [level, line] : lines.lines)
        answered |= level == LogLevel::info &&
                    line.find("camera 127.0.0.1 answers again") != std::string::npos;
    EXPECT_TRUE(answered);
}

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
        fpp::test::scanner_exe(),
        "--board " + fpp::test::shell_quote(board) + " --once --mode capture", scratch.path());
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
        fpp::test::scanner_exe(),
        "--board " + fpp::test::shell_quote(board2) + " --once --mode capture", scratch.path());
    EXPECT_EQ(run2.exit_code, 1) << run2.output;
    EXPECT_NE(run2.output.find("error: gpiochip0"), std::string::npos) << run2.output;
    EXPECT_FALSE(fs::exists(dir / "scans") && !fs::is_empty(dir / "scans"));
}

#else

TEST(ScannerGige, NotBuilt) {
    if (fpp::test::in_ci())
        FAIL() << "fpp_aravis is not linked to this test";
    GTEST_SKIP() << "the Aravis driver is not built (aravis-0.8 not found)";
}

#endif
