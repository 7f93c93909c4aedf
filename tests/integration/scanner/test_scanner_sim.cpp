// The scanner firmware end to end on the virtual scanner: the scan loop over
// the sim display, trigger line and camera, the table, the scan store, the
// board file, faults, and the fpp-scanner binary.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "fpp/coefficient_table.hpp"
#include "fpp/drivers/device_error.hpp"
#include "fpp/error.hpp"
#include "fpp/patterns.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/scanner/api_events.hpp"
#include "fpp/scanner/board_config.hpp"
#include "fpp/scanner/scan_store.hpp"
#include "fpp/scanner/scanner.hpp"
#include "fpp/scanner/scanner_service.hpp"
#include "fpp/scanner/sim_board.hpp"
#include "fpp/sim/observed_display.hpp"
#include "fpp/sim/sim_camera.hpp"
#include "fpp/sim/sim_clock.hpp"
#include "fpp/sim/sim_display.hpp"
#include "rig_truth_table.hpp"
#include "sim_board_yaml.hpp"
#include "test_support.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fcntl.h>
#include <fstream>
#include <mutex>
#include <signal.h>
#include <sstream>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace fpp;
using namespace fpp::scanner;
using drivers::LedState;

namespace {

// The test board: camera binned 4 x 4 (400 x 300), virtual clock.
std::string board_yaml(const fs::path& store, const std::string& table = "") {
    fpp::test::SimBoardYaml b;
    b.store = store;
    b.table = table;
    return b.text();
}

void write_text(const fs::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

// A sim board in a temporary folder, its table made from the rig's truth.
struct Fixture {
    fpp::test::TempDir dir;
    fs::path board_file = dir / "board.yaml";
    fs::path store = dir / "scans";
    fs::path table_file = dir / "table.fpt";
    BoardConfig board;
    std::vector<std::string> lines;
    std::mutex lines_mutex;
    Logger log{[this](LogLevel level, const std::string& m) {
        std::lock_guard lock(lines_mutex);
        lines.push_back(std::to_string(int(level)) + " " + m);
    }};

    explicit Fixture(bool with_table = true) {
        write_text(board_file, board_yaml(store, with_table ? "table.fpt" : ""));
        board = read_board_config(board_file);
    }
    void make_table(const sim::Rig& rig, const TableTrueness& trueness = {}) {
        write_table(table_file, fpp::test::rig_truth_table(rig, trueness));
    }
    // The table of the board's own rig (a sim board is built for it and let go).
    void make_board_table() {
        SimBoard sim(board);
        make_table(sim.rig());
    }
    // fpp-scanner --board board.yaml --once, as a person runs it.
    fpp::test::ToolRun run_once(const fpp::test::TempDir& scratch) const {
        return fpp::test::run_tool(fpp::test::scanner_exe(),
                                   "--board " + fpp::test::shell_quote(board_file) + " --once",
                                   scratch.path());
    }
    bool logged(const std::string& part) {
        std::lock_guard lock(lines_mutex);
        for (const auto& l : lines)
            if (l.find(part) != std::string::npos)
                return true;
        return false;
    }
};

} // namespace

TEST(ScannerSim, ScanWritesCloudCloseToTruth) {
    Fixture f;
    SimBoard sim(f.board);
    // A table that carries its calibration's predicted trueness.
    f.make_table(sim.rig(), {150.0f, 478.5f, 0.0191f, 0.0034f});
    Scanner scanner(f.board, sim.devices(), f.log);
    const ScanOutcome out = scanner.scan(ScanMode::scan);

    ASSERT_TRUE(fs::exists(out.folder / "cloud.ply"));
    ASSERT_TRUE(fs::exists(out.folder / "scan.json"));
    EXPECT_EQ(out.attempts, 1);
    EXPECT_EQ(out.frames, scanner.frames_per_scan());
    // The composite scene fills most of the 400 x 300 binned image.
    EXPECT_GT(out.points, 60000u);
    std::size_t compared = 0;
    const double rms = fpp::test::ply_rms_against_truth(out.folder / "cloud.ply",
                                                        sim.renderer().truth_xyz(), compared);
    std::printf("scan: %zu points, RMS %.4f mm against truth over %zu; streaming %.3f ms/frame, "
                "last frame to disk %.1f ms\n",
                out.points, rms, compared, out.timings.push_mean_ms,
                out.timings.last_frame_to_written_ms);
    EXPECT_GT(compared, out.points * 9 / 10);
    EXPECT_LT(rms, 0.1);

    // scan.json counts the decode (fpp/decode_report.hpp): nearly every lit pixel decodes.
    std::stringstream scan_json;
    scan_json << std::ifstream(out.folder / "scan.json").rdbuf();
    const std::string json = scan_json.str();
    const auto coverage_at = json.find("\"coverage_of_lit\": ");
    ASSERT_NE(coverage_at, std::string::npos) << json;
    const double coverage = std::strtod(json.c_str() + coverage_at + 19, nullptr);
    std::printf("scan.json: coverage of lit %.4f\n", coverage);
    EXPECT_GT(coverage, 0.99);
    EXPECT_NE(json.find("\"statistics_of\": \"pass\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"unwrap_inconsistent\": "), std::string::npos) << json;
    // The table's trueness, as scan-json.md gives it.
    const nlohmann::json meta = nlohmann::json::parse(json);
    const nlohmann::json& trueness = meta.at("table").at("trueness");
    EXPECT_EQ(trueness.at("length_mm").get<double>(), 150);
    EXPECT_EQ(trueness.at("depth_mm").get<double>(), 478.5);
    EXPECT_EQ(trueness.at("sigma_along_depth_mm").get<double>(), 0.0191);
    EXPECT_EQ(trueness.at("sigma_across_mm").get<double>(), 0.0034);
    EXPECT_EQ(trueness.at("along_depth_ppm").get<double>(), 127);
    EXPECT_EQ(trueness.at("across_ppm").get<double>(), 23);

    // Every frame shows the pattern it was triggered for, over the whole exposure.
    const auto& exposures = sim.camera().exposures();
    ASSERT_EQ(exposures.size(), std::size_t(out.frames));
    for (std::size_t i = 0; i < exposures.size(); ++i) {
        EXPECT_EQ(exposures[i].pattern, int(i));
        EXPECT_EQ(exposures[i].pattern_at_end, int(i));
    }
    EXPECT_EQ(sim.led().state(), LedState::ready);
    const auto history = sim.led().history();
    EXPECT_NE(std::find(history.begin(), history.end(), LedState::scanning), history.end());
    EXPECT_FALSE(sim.camera().streaming());
}

TEST(ScannerSim, TriggerBeforeFlipCompletesCapturesWrongPattern) {
    Fixture f(false);
    SimBoard sim(f.board);
    const auto patterns =
        render_sequence(f.board.sequence(sim.display().size()), sim.display().size());
    sim.display().prepare(patterns);
    sim.camera().start();
    sim.display().show(0);
    sim.display().wait_flip(std::chrono::milliseconds(100));
    sim.trigger().pulse(std::chrono::microseconds(100));
    sim.camera().next_frame(std::chrono::milliseconds(100));
    // Pattern 1 queued but not yet on screen: the exposure sees pattern 0.
    sim.display().show(1);
    sim.trigger().pulse(std::chrono::microseconds(100));
    const drivers::CapturedFrame early = sim.camera().next_frame(std::chrono::milliseconds(100));
    ASSERT_EQ(sim.camera().exposures().size(), 2u);
    EXPECT_EQ(sim.camera().exposures()[1].pattern, 0) << "a trigger before the flip saw pattern 1";
    // A second flip while one is pending is refused.
    EXPECT_THROW(sim.display().show(2), drivers::DeviceError);
    const drivers::FlipEvent flip = sim.display().wait_flip(std::chrono::milliseconds(100));
    EXPECT_EQ(flip.index, 1u);
    EXPECT_LT(early.timestamp_ns, flip.timestamp_ns);
}

TEST(ScannerSim, CameraSeeingADisplayThroughItsFlipEventsScansAsTheSimBoard) {
    // What a camera_only board does with a real display, with the sim
    // display in its place: the camera renders what the flip events say is
    // on screen, triggered from software.
    Fixture f;
    SimBoard sim(f.board);
    f.make_table(sim.rig());
    f.board.camera.settings.trigger = drivers::TriggerMode::software;
    sim::VirtualClock clock;
    sim::SimDisplay display(sim.rig().projector_size, clock);
    sim::ObservedDisplay observed(display);
    sim::SimCamera camera(sim.renderer(), observed, clock, f.board.camera.settings, 3);
    Scanner scanner(
        f.board, Devices{observed, sim.trigger(), sim.button(), sim.led(), camera, clock}, f.log);
    const ScanOutcome out = scanner.scan(ScanMode::scan);
    std::size_t compared = 0;
    const double rms = fpp::test::ply_rms_against_truth(out.folder / "cloud.ply",
                                                        sim.renderer().truth_xyz(), compared);
    EXPECT_GT(out.points, 60000u);
    EXPECT_LT(rms, 0.1);
    ASSERT_EQ(camera.exposures().size(), static_cast<std::size_t>(out.frames));
    for (std::size_t i = 0; i < camera.exposures().size(); ++i) {
        EXPECT_EQ(camera.exposures()[i].pattern, static_cast<int>(i));
        // The observer agrees with the display's own schedule.
        EXPECT_EQ(display.on_screen_at(camera.exposures()[i].start_ns), static_cast<int>(i));
    }
}

TEST(ScannerSim, EarlyFlipEventsAreCaughtAsPatternMismatch) {
    // A display whose events arrive 5 ms before the pattern is on screen, with
    // 2 ms of settle: frames show the previous pattern.
    Fixture f;
    SimBoard sim(f.board);
    f.make_table(sim.rig());
    sim.display().set_event_lead(std::chrono::milliseconds(5));
    Scanner scanner(f.board, sim.devices(), f.log);
    scanner.scan(ScanMode::scan);
    int mismatched = 0;
    const auto& exposures = sim.camera().exposures();
    for (std::size_t i = 0; i < exposures.size(); ++i)
        mismatched += exposures[i].pattern != int(i);
    EXPECT_EQ(mismatched, int(exposures.size()));
}

TEST(ScannerSim, CaptureModeWritesCaptureSetWithoutTable) {
    Fixture f(false);
    SimBoard sim(f.board);
    Scanner scanner(f.board, sim.devices(), f.log);
    EXPECT_THROW(scanner.scan(ScanMode::scan), InputError); // no table
    EXPECT_TRUE(list_scans(f.store).empty());
    const ScanOutcome out = scanner.scan(ScanMode::capture);
    const CaptureSet set = read_capture_set(out.folder / "capture");
    EXPECT_EQ(int(set.frames.size()), scanner.frames_per_scan());
    EXPECT_EQ(set.manifest.camera, sim.rig().camera_size);
    EXPECT_FALSE(fs::exists(out.folder / "cloud.ply"));
}

TEST(ScannerSim, CameraGoneMidScanFailsWithoutOutput) {
    Fixture f;
    SimBoard sim(f.board);
    f.make_table(sim.rig());
    Scanner scanner(f.board, sim.devices(), f.log);
    sim.camera().inject_fault(sim::CameraFault::gone, 5);
    EXPECT_THROW(scanner.scan(ScanMode::scan), drivers::DeviceError);
    EXPECT_EQ(sim.led().state(), LedState::error);
    EXPECT_TRUE(f.logged("scan failed: sim camera: camera gone"));
    EXPECT_TRUE(list_scans(f.store).empty());
    EXPECT_TRUE(fs::is_empty(f.store)); // no temporary leftovers either
}

TEST(ScannerSim, FrameTimeoutAndDroppedFrameAreRetriedOnce) {
    for (auto fault :
         {sim::CameraFault::timeout, sim::CameraFault::dropped, sim::CameraFault::incomplete}) {
        Fixture f;
        SimBoard sim(f.board);
        f.make_table(sim.rig());
        Scanner scanner(f.board, sim.devices(), f.log);
        sim.camera().inject_fault(fault, 7);
        const ScanOutcome out = scanner.scan(ScanMode::scan);
        EXPECT_EQ(out.attempts, 2);
        EXPECT_TRUE(f.logged("retrying once"));
        EXPECT_EQ(list_scans(f.store).size(), 1u);
        EXPECT_EQ(sim.led().state(), LedState::ready);
    }
    {
        Fixture f;
        SimBoard sim(f.board);
        f.make_table(sim.rig());
        Scanner scanner(f.board, sim.devices(), f.log);
        sim.camera().inject_fault(sim::CameraFault::dropped, 3);
        const ScanOutcome out = scanner.scan(ScanMode::scan);
        EXPECT_TRUE(f.logged("a frame was dropped"));
        EXPECT_EQ(out.attempts, 2);
    }
}

TEST(ScannerSim, ATriggerThatFiresTwiceIsSeenAndTheScanRetried) {
    // One trigger, two exposures (a software trigger command sent again after
    // its acknowledgement was lost on the link; a glitch on the trigger line):
    // every later frame comes one pattern late, and its frame id follows on.
    // Mid-scan (seen before the next trigger) and at the last of the 17
    // triggers (seen as a frame left over).
    for (const auto& [trigger, at] : {std::pair<std::string, int>{"line", 4}, {"software", 16}}) {
        SCOPED_TRACE(trigger + " trigger, fault at trigger " + std::to_string(at));
        Fixture f;
        std::string text = board_yaml(f.store, "table.fpt");
        text.replace(text.find("trigger: line"), 13, "trigger: " + trigger);
        write_text(f.board_file, text);
        f.board = read_board_config(f.board_file);
        SimBoard sim(f.board);
        f.make_table(sim.rig());
        Scanner scanner(f.board, sim.devices(), f.log);
        sim.camera().inject_fault(sim::CameraFault::doubled, at);
        const ScanOutcome out = scanner.scan(ScanMode::scan);
        EXPECT_EQ(out.attempts, 2);
        EXPECT_TRUE(f.logged("a trigger fired twice"));
        // The scan written is the retried one, every frame of it taken
        // under its own pattern.
        const auto& exposures = sim.camera().exposures();
        ASSERT_EQ(exposures.size(), std::size_t(at + 2 + 17));
        for (std::size_t i = 0; i < 17; ++i)
            EXPECT_EQ(exposures[exposures.size() - 17 + i].pattern, int(i)) << i;
        EXPECT_EQ(list_scans(f.store).size(), 1u);
        // Nothing of the failed attempt stays in the decoder.
        std::size_t compared = 0;
        const double rms = fpp::test::ply_rms_against_truth(out.folder / "cloud.ply",
                                                            sim.renderer().truth_xyz(), compared);
        std::printf("%s trigger doubled at %d: RMS %.4f mm over %zu points\n", trigger.c_str(), at,
                    rms, compared);
        EXPECT_LT(rms, 0.1);
        EXPECT_GT(out.points, 60000u);
    }
}

TEST(ScannerSim, FrameIdsWrappingAt16BitsFollowEachOtherAndAGapAcrossTheWrapIsSeen) {
    // A GigE Vision 1.x camera's block id goes 65534, 65535, 1, 2: one scan
    // every 65,535 frames (3,855 scans of 17) crosses it.
    Fixture f;
    SimBoard sim(f.board);
    f.make_table(sim.rig());
    Scanner scanner(f.board, sim.devices(), f.log);
    sim.camera().set_next_frame_id(65530, true);
    const ScanOutcome out = scanner.scan(ScanMode::scan);
    EXPECT_EQ(out.attempts, 1);
    const auto& exposures = sim.camera().exposures();
    ASSERT_EQ(exposures.size(), 17u);
    EXPECT_EQ(exposures[5].frame_id, 65535u);
    EXPECT_EQ(exposures[6].frame_id, 1u);
    // The frame after 65535 lost: seen, and the scan retried.
    sim.camera().set_next_frame_id(65530, true);
    sim.camera().inject_fault(sim::CameraFault::dropped, 17 + 6);
    const ScanOutcome again = scanner.scan(ScanMode::scan);
    EXPECT_TRUE(f.logged("frame id 2 after 65535: a frame was dropped"));
    EXPECT_EQ(again.attempts, 2);
    EXPECT_THROW(sim.camera().set_next_frame_id(0, false), std::invalid_argument);
    EXPECT_THROW(sim.camera().set_next_frame_id(65536, true), std::invalid_argument);
}

TEST(ScannerSim, FlipFailureAndStopRequestLeaveNothing) {
    Fixture f;
    SimBoard sim(f.board);
    f.make_table(sim.rig());
    Scanner scanner(f.board, sim.devices(), f.log);
    sim.display().fail_next_flip();
    EXPECT_THROW(scanner.scan(ScanMode::scan), drivers::DeviceError);
    EXPECT_EQ(sim.led().state(), LedState::error);
    EXPECT_TRUE(f.logged("page flip failed"));

    std::atomic<bool> stop{false};
    sim.display().on_flip([&](const drivers::FlipEvent& e) {
        if (e.index == 4)
            stop = true;
    });
    EXPECT_THROW(scanner.scan(ScanMode::scan, &stop), ScanAborted);
    EXPECT_TRUE(list_scans(f.store).empty());
    EXPECT_FALSE(sim.camera().streaming());
}

TEST(ScannerSim, BadTablesAreRejectedNamingTheFile) {
    Fixture f;
    SimBoard sim(f.board);
    // Missing.
    try {
        Scanner scanner(f.board, sim.devices(), f.log);
        FAIL() << "missing table accepted";
    } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find("table.fpt"), std::string::npos) << e.what();
    }
    // Corrupt: a valid table with one byte flipped in a tile.
    f.make_table(sim.rig());
    {
        std::fstream io(f.table_file, std::ios::in | std::ios::out | std::ios::binary);
        io.seekp(std::streamoff(fs::file_size(f.table_file) / 2));
        io.put('\x5a');
    }
    EXPECT_THROW(Scanner(f.board, sim.devices(), f.log), InputError);
    // For another camera resolution.
    write_table(f.table_file, fpp::test::rig_truth_table(sim.rig().binned_camera(2)));
    EXPECT_THROW(Scanner(f.board, sim.devices(), f.log), InputError);
}

TEST(ScannerSim, ButtonDuringScanIsIgnoredAndLogged) {
    Fixture f;
    SimBoard sim(f.board);
    f.make_table(sim.rig());
    Scanner scanner(f.board, sim.devices(), f.log);
    EventHub events;
    ApiEvents rendered(events);
    ScannerService service(f.board, scanner, sim.devices(), rendered, f.log, {});
    sim.display().on_flip([&](const drivers::FlipEvent& e) {
        if (e.index == 3)
            sim.button().press(2); // one press, two bounces
    });
    std::atomic<bool> stop{false};
    sim.button().press();
    std::thread loop([&] { service.run(ScanMode::scan, stop); });
    for (int i = 0; i < 600 && !f.logged("during the scan: ignored"); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    stop = true;
    loop.join();
    EXPECT_TRUE(f.logged("button pressed 1 time(s) during the scan: ignored"));
    EXPECT_EQ(service.status().scans_completed, 1);
    EXPECT_EQ(list_scans(f.store).size(), 1u);
}

TEST(ScannerSim, StorePrunedToItsLimit) {
    fpp::test::TempDir dir;
    for (const char* name :
         {"scan-20200101-000000-000", "scan-20200102-000000-000", "scan-20200103-000000-000"}) {
        fs::create_directories(dir / name);
        write_text(dir / name / "cloud.ply", std::string(1000, 'x'));
    }
    const auto removed = prune_store(dir.path(), 2000, dir / "scan-20200101-000000-000");
    ASSERT_EQ(removed.size(), 1u);
    EXPECT_EQ(removed[0].filename(), "scan-20200102-000000-000");
}

TEST(ScannerCli, OnceWritesOutputsAndFailsCleanlyWithoutTable) {
    Fixture f;
    f.make_board_table();
    fpp::test::TempDir scratch;
    const auto ok = f.run_once(scratch);
    ASSERT_EQ(ok.exit_code, 0) << ok.output;
    const auto scans = list_scans(f.store);
    ASSERT_EQ(scans.size(), 1u);
    EXPECT_NE(ok.output.find(scans[0].string()), std::string::npos) << ok.output;
    EXPECT_TRUE(fs::exists(scans[0] / "cloud.ply"));

    fs::remove(f.table_file);
    const auto bad = f.run_once(scratch);
    EXPECT_EQ(bad.exit_code, 1) << bad.output;
    EXPECT_NE(bad.output.find("error: " + f.table_file.string()), std::string::npos) << bad.output;
    EXPECT_EQ(list_scans(f.store).size(), 1u);
}

// The store on a file system of its own, in a private mount namespace of the
// child: read-only (a bind mount remounted ro), or full (a 256 KiB tmpfs,
// which a 400 x 300 cloud overflows). Both need CAP_SYS_ADMIN (root in CI);
// chmod alone would not stop root.
namespace {

fpp::test::ToolRun run_with_store_mount(const Fixture& f, const std::string& mount_commands,
                                        const fpp::test::TempDir& scratch) {
    const std::string store = fpp::test::shell_quote(f.store);
    const std::string script = "set -e; " + mount_commands + "; exec " +
                               fpp::test::shell_quote(fpp::test::scanner_exe()) + " --board " +
                               fpp::test::shell_quote(f.board_file) + " --once";
    return fpp::test::run_tool("unshare", "-m sh -c " + fpp::test::shell_quote(script),
                               scratch.path());
}

bool can_mount_privately() {
    return std::system("unshare -m true > /dev/null 2>&1") == 0;
}

} // namespace

TEST(ScannerCli, ReadOnlyOrFullStoreFailsCleanlyAndLeavesNothing) {
    if (!can_mount_privately()) {
        if (fpp::test::in_ci())
            FAIL() << "unshare -m is not permitted";
        GTEST_SKIP() << "needs a private mount namespace (unshare -m, root)";
    }
    Fixture f;
    f.make_board_table();
    fpp::test::TempDir scratch;
    // One good scan first: the faults must leave it alone.
    const auto ok = f.run_once(scratch);
    ASSERT_EQ(ok.exit_code, 0) << ok.output;
    ASSERT_EQ(list_scans(f.store).size(), 1u);
    const auto before = list_scans(f.store);
    const std::string store = fpp::test::shell_quote(f.store);

    const auto ro = run_with_store_mount(
        f, "mount --bind " + store + " " + store + "; mount -o remount,bind,ro " + store, scratch);
    EXPECT_EQ(ro.exit_code, 1) << ro.output;
    EXPECT_NE(ro.output.find("error: "), std::string::npos) << ro.output;
    EXPECT_NE(ro.output.find(f.store.string()), std::string::npos) << ro.output;
    EXPECT_NE(ro.output.find("Read-only file system"), std::string::npos) << ro.output;
    EXPECT_EQ(list_scans(f.store), before);

    // A full disk: the tmpfs hides the store's contents while mounted.
    const auto full =
        run_with_store_mount(f, "mount -t tmpfs -o size=256k fpp-full " + store, scratch);
    EXPECT_EQ(full.exit_code, 1) << full.output;
    EXPECT_NE(full.output.find("error: "), std::string::npos) << full.output;
    EXPECT_NE(full.output.find("No space left on device"), std::string::npos) << full.output;
    EXPECT_EQ(full.output.find("scan written"), std::string::npos) << full.output;
    // Back on the real store: the earlier scan and nothing else.
    EXPECT_EQ(list_scans(f.store), before);
    std::size_t entries = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(f.store))
        ++entries;
    EXPECT_EQ(entries, 1u);
}

TEST(ScannerCli, SigtermDuringAScanAbortsItCleanly) {
    // Slow flips (0.1 s each, steady clock): the 17-pattern scan takes about
    // 2 s, and SIGTERM arrives as soon as the scan has started.
    Fixture f;
    f.make_board_table();
    std::string text = board_yaml(f.store, "table.fpt");
    text.replace(text.find("flip_latency_us: 16667, clock: virtual"), 38,
                 "flip_latency_us: 100000, clock: steady");
    write_text(f.board_file, text);
    const fs::path log = f.dir / "scanner.log";
    const std::string board = f.board_file.string(); // no allocation after fork()
    const std::string scanner = fpp::test::scanner_exe();
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (fd < 0 || dup2(fd, STDERR_FILENO) < 0 || dup2(fd, STDOUT_FILENO) < 0)
            _exit(127);
        execl(scanner.c_str(), scanner.c_str(), "--board", board.c_str(), "--once",
              static_cast<char*>(nullptr));
        _exit(127);
    }
    auto read_log = [&] {
        std::ifstream in(log);
        std::stringstream ss;
        ss << in.rdbuf();
        return ss.str();
    };
    bool started = false;
    for (int i = 0; i < 10000 && !started; ++i) { // up to 10 s
        started = read_log().find("scan started") != std::string::npos;
        if (!started)
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    ASSERT_TRUE(started) << read_log();
    ASSERT_EQ(kill(pid, SIGTERM), 0);
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status) << "\n" << read_log();
    EXPECT_EQ(WEXITSTATUS(status), 1) << read_log();
    const std::string out = read_log();
    EXPECT_NE(out.find("abort"), std::string::npos) << out;
    EXPECT_EQ(out.find("scan written"), std::string::npos) << out;
    EXPECT_TRUE(!fs::exists(f.store) || fs::is_empty(f.store)) << out;
}
