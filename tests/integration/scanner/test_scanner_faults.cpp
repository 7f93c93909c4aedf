// Faults a scanner meets in the field, met by the running service (the
// daemon's ScannerService loop, in process, never restarted): the store's
// disk full or read-only, the table file copied over or damaged on disk, the
// projector's output disconnected, the GPIO chip gone. Each ends in the
// error state with its reason, leaves nothing half written, and the first
// scan after the fault is gone succeeds. (The camera's loss and return: ScannerGige.CameraLost*;
// power cuts: ScannerPowerCut.*.)
#include <gtest/gtest.h>

#include "fpp/coefficient_table.hpp"
#include "fpp/fnv1a.hpp"
#include "fpp/scanner/api_error.hpp"
#include "fpp/scanner/scan_store.hpp"
#include "fpp/yaml_fields.hpp"
#include "running_service.hpp"
#include "test_support.hpp"

#include <sched.h>
#include <sys/mount.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using namespace fpp;
using namespace fpp::scanner;
using fpp::test::next_event;
using fpp::test::RunningService;

namespace {

// Before main(), while the process has one thread (every thread after it
// shares the namespace): mounts made by this test program are its own.
// False where that is not permitted (no CAP_SYS_ADMIN).
const bool private_mounts = [] {
    if (::unshare(CLONE_NEWNS) != 0)
        return false;
    return ::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) == 0;
}();

// A scan requested as a client would, and the event that ends it.
std::pair<std::string, std::string> scan_through_api(RunningService& rs) {
    rs.service->start_scan(ScanMode::scan);
    const auto end = next_event(*rs.stream, {"written", "failed"});
    if (!end)
        return {"(no event within 60 s)", ""};
    return *end;
}

double rms_against_truth(RunningService& rs, const fs::path& scan) {
    std::size_t compared = 0;
    return fpp::test::ply_rms_against_truth(scan / "cloud.ply", rs.sim.renderer().truth_xyz(),
                                            compared);
}

void require_private_mounts() {
    if (private_mounts)
        return;
    if (fpp::test::in_ci())
        FAIL() << "unshare(CLONE_NEWNS) is not permitted";
    GTEST_SKIP() << "needs a private mount namespace (CAP_SYS_ADMIN, root)";
}

} // namespace

TEST(ScannerFaults, FullThenReadOnlyStoreFailsCleanlyAndTheNextScanAfterItSucceeds) {
    require_private_mounts();
    fpp::test::Journal journal;
    RunningService rs(journal.sink());
    const fs::path store = rs.store();
    ASSERT_EQ(scan_through_api(rs).first, "written");
    ASSERT_EQ(list_scans(store).size(), 1u);

    // The disk fills: a 256 KiB tmpfs over the store, which a 400 x 300
    // cloud overflows.
    ASSERT_EQ(::mount("fpp-full", store.c_str(), "tmpfs", 0, "size=256k"), 0)
        << std::strerror(errno);
    auto [name, data] = scan_through_api(rs);
    EXPECT_EQ(name, "failed");
    EXPECT_NE(data.find("No space left on device"), std::string::npos) << data;
    EXPECT_EQ(rs.service->state().state, ScannerState::error);
    EXPECT_EQ(rs.sim.led().state(), drivers::LedState::error);
    // Nothing half written on the full disk: not a file, not a folder.
    EXPECT_TRUE(fpp::test::entries_under(store).empty()) << fpp::test::entries_under(store).front();
    EXPECT_TRUE(list_scans(store).empty());
    // Space again (the tmpfs gone): the next scan is written.
    ASSERT_EQ(::umount2(store.c_str(), 0), 0) << std::strerror(errno);
    EXPECT_EQ(scan_through_api(rs).first, "written");
    EXPECT_EQ(list_scans(store).size(), 2u);
    EXPECT_EQ(rs.service->state().state, ScannerState::idle);
    EXPECT_EQ(rs.sim.led().state(), drivers::LedState::ready);

    // The store's file system goes read-only (a read-only bind mount of it).
    const auto before = list_scans(store);
    ASSERT_EQ(::mount(store.c_str(), store.c_str(), nullptr, MS_BIND, nullptr), 0);
    ASSERT_EQ(::mount(nullptr, store.c_str(), nullptr, MS_REMOUNT | MS_BIND | MS_RDONLY, nullptr),
              0)
        << std::strerror(errno);
    // Refused when the scan is asked for: the store is checked writable
    // before a scan is queued (507, as the API says for storage errors).
    try {
        rs.service->start_scan(ScanMode::scan);
        ADD_FAILURE() << "a scan was queued on a read-only store";
    } catch (const ApiError& e) {
        EXPECT_EQ(e.status(), 507);
        EXPECT_NE(std::string(e.what()).find("Read-only file system"), std::string::npos)
            << e.what();
    }
    EXPECT_EQ(list_scans(store), before);
    ASSERT_EQ(::umount2(store.c_str(), 0), 0) << std::strerror(errno);
    EXPECT_EQ(scan_through_api(rs).first, "written");
    EXPECT_EQ(list_scans(store).size(), 3u);
    EXPECT_EQ(rs.service->state().state, ScannerState::idle);
    // Every scan left is whole: its cloud close to the truth.
    for (const auto& scan : list_scans(store))
        EXPECT_LT(rms_against_truth(rs, scan), 0.1) << scan;
}

TEST(ScannerFaults, TableChangedOnDiskIsReloadedAndADamagedOneStopsScansUntilWholeAgain) {
    fpp::test::Journal journal;
    RunningService rs(journal.sink());
    const fs::path table = rs.dir / "table.fpt";
    const fs::path store = rs.store();
    ASSERT_EQ(scan_through_api(rs).first, "written");
    EXPECT_LT(rms_against_truth(rs, list_scans(store).back()), 0.1);
    const std::string good = fpp::yaml_fields::read_text_file(table);

    // Another table copied over it in place, as `cp other.fpt table.fpt`
    // does (truncate, write): every depth 5 mm further (Z0 + 5: the
    // rational model's numerator). The next scan uses it.
    CoefficientTable shifted = fpp::test::rig_truth_table(rs.sim.rig());
    const Size cam = shifted.info().camera;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x)
            if (shifted.has_model(x, y))
                shifted.set(table_plane::rational_z, x, y,
                            shifted.get(table_plane::rational_z, x, y) + 5.0f);
    const fs::path other = rs.dir / "other.fpt";
    write_table(other, shifted);
    const std::string other_bytes = fpp::yaml_fields::read_text_file(other);
    std::ofstream(table, std::ios::binary | std::ios::trunc) << other_bytes;
    ASSERT_EQ(scan_through_api(rs).first, "written");
    EXPECT_TRUE(journal.count("table " + table.string() + " changed on disk: reloaded") > 0);
    const double shifted_rms = rms_against_truth(rs, list_scans(store).back());
    std::printf("scan with the table copied over: RMS %.2f mm against truth\n", shifted_rms);
    EXPECT_GT(shifted_rms, 3.0);
    EXPECT_LT(shifted_rms, 7.0);
    ASSERT_TRUE(rs.service->table());
    EXPECT_EQ(rs.service->table()->file_hash, fnv1a64(other_bytes.data(), other_bytes.size()));

    // Damaged in place: one byte of the coefficients flipped. Scans stop
    // with the loader's reason (the file and the tile), nothing written.
    {
        std::fstream f(table, std::ios::binary | std::ios::in | std::ios::out);
        f.seekp(static_cast<std::streamoff>(other_bytes.size() / 2));
        f.put(static_cast<char>(other_bytes[other_bytes.size() / 2] ^ 0x5a));
    }
    const std::size_t written_before = list_scans(store).size();
    for (int k = 0; k < 2; ++k) {
        const auto [name, data] = scan_through_api(rs);
        EXPECT_EQ(name, "failed") << k;
        EXPECT_NE(data.find(table.string()), std::string::npos) << data;
        EXPECT_NE(data.find("crc"), std::string::npos) << data;
        EXPECT_EQ(rs.service->state().state, ScannerState::error);
        EXPECT_EQ(rs.sim.led().state(), drivers::LedState::error);
    }
    EXPECT_EQ(list_scans(store).size(), written_before);
    EXPECT_TRUE(journal.count("changed on disk and cannot be used") > 0);

    // Gone: the same, naming the file.
    fs::remove(table);
    const auto gone = scan_through_api(rs);
    EXPECT_EQ(gone.first, "failed");
    EXPECT_NE(gone.second.find(table.string()), std::string::npos) << gone.second;

    // Whole again (the good table put back): scans go on, close to truth.
    std::ofstream(table, std::ios::binary | std::ios::trunc) << good;
    ASSERT_EQ(scan_through_api(rs).first, "written");
    EXPECT_LT(rms_against_truth(rs, list_scans(store).back()), 0.1);
    EXPECT_EQ(rs.service->state().state, ScannerState::idle);
    EXPECT_EQ(list_scans(store).size(), written_before + 1);
}

TEST(ScannerFaults, DisplayDisconnectedFailsTheScanAndItsReturnEndsTheError) {
    fpp::test::Journal journal;
    RunningService rs(journal.sink());
    const fs::path store = rs.store();
    ASSERT_EQ(scan_through_api(rs).first, "written");

    rs.sim.display().set_connected(false);
    const auto [name, data] = scan_through_api(rs);
    EXPECT_EQ(name, "failed");
    EXPECT_NE(data.find("sim display: page flip refused: the output is disconnected"),
              std::string::npos)
        << data;
    EXPECT_EQ(rs.service->state().state, ScannerState::error);
    EXPECT_EQ(rs.sim.led().state(), drivers::LedState::error);
    EXPECT_EQ(list_scans(store).size(), 1u);

    rs.sim.display().set_connected(true);
    ASSERT_EQ(scan_through_api(rs).first, "written");
    EXPECT_EQ(rs.service->state().state, ScannerState::idle);
    EXPECT_EQ(list_scans(store).size(), 2u);
    EXPECT_LT(rms_against_truth(rs, list_scans(store).back()), 0.1);
}

// The chip of the button and the trigger goes away while the scanner is
// idle (on the device: the driver unbound, a module unloaded; the VM tests
// do it to the PL061, VM.ArmBoardDevicesWork): the scanner says so within a
// poll, stays up, says it once, fails a scan through the API naming the
// trigger, and ends the error by itself when the chip is back; then the
// button scans again.
TEST(ScannerFaults, GpioChipGoneIsAnErrorUntilItReturnsThenTheButtonScans) {
    fpp::test::Journal journal;
    RunningService rs(journal.sink());
    const auto state = [&] { return std::string(to_string(rs.service->status().state.state)); };
    const auto wait_for_state = [&](const std::string& wanted) {
        for (int i = 0; i < 100 && state() != wanted; ++i)
            std::this_thread::sleep_for(std::chrono::milliseconds(30));
        return state();
    };

    rs.sim.button().set_connected(false);
    rs.sim.trigger().set_connected(false);
    ASSERT_EQ(wait_for_state("error"), "error");
    EXPECT_EQ(rs.service->state().error, "sim button: reading an edge failed: the chip went away");
    EXPECT_EQ(rs.sim.led().state(), drivers::LedState::error);

    auto [name, data] = scan_through_api(rs);
    EXPECT_EQ(name, "failed");
    EXPECT_NE(data.find("sim trigger: cannot open the chip"), std::string::npos) << data;
    EXPECT_TRUE(list_scans(rs.store()).empty());
    // Asked again once a second (2.5 s: at least two more tries), said once,
    // and back in the error state after the failed scan's own error.
    std::this_thread::sleep_for(std::chrono::milliseconds(2500));
    EXPECT_EQ(journal.count("button: sim button: reading an edge failed"), 1);
    EXPECT_EQ(rs.service->state().error, "sim button: reading an edge failed: the chip went away");
    rs.sim.button().press(); // lost: no chip, no edge
    EXPECT_EQ(journal.count("button answers again"), 0);

    rs.sim.button().set_connected(true);
    rs.sim.trigger().set_connected(true);
    // Within the retry second (and a poll).
    const auto back = std::chrono::steady_clock::now();
    ASSERT_EQ(wait_for_state("idle"), "idle");
    EXPECT_LT(std::chrono::steady_clock::now() - back, std::chrono::milliseconds(1500));
    EXPECT_EQ(journal.count("button answers again"), 1);
    EXPECT_EQ(rs.sim.led().state(), drivers::LedState::ready);
    EXPECT_TRUE(list_scans(rs.store()).empty()); // the press made while away started nothing

    rs.sim.button().press();
    const auto end = next_event(*rs.stream, {"written", "failed"});
    ASSERT_TRUE(end.has_value());
    EXPECT_EQ(end->first, "written") << end->second;
    ASSERT_EQ(list_scans(rs.store()).size(), 1u);
    EXPECT_LT(rms_against_truth(rs, list_scans(rs.store()).back()), 0.1);
}
