// Scan folder names when the wall clock jumps back: they stay unique and
// sort after every scan in the store, so that pruning (oldest name first)
// never removes the newest scans.
#include <gtest/gtest.h>

#include "fpp/error.hpp"
#include "fpp/scanner/scan_store.hpp"
#include "test_support.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

namespace fs = std::filesystem;
using namespace std::chrono;
using fpp::scanner::list_scans;
using fpp::scanner::new_scan_folder;
using fpp::scanner::prune_store;

namespace {

// 2026-11-27 03:00:00.250 UTC plus `offset`.
system_clock::time_point at(milliseconds offset) {
    return system_clock::time_point(seconds(1795748400)) + milliseconds(250) + offset;
}

// A scan folder with `bytes` bytes of cloud.
fs::path make_scan(const fs::path& folder, std::size_t bytes) {
    fs::create_directories(folder);
    std::ofstream(folder / "cloud.ply") << std::string(bytes, 'x');
    return folder;
}

} // namespace

TEST(ScanStore, NamesFollowTheClockWhileItMovesOn) {
    fpp::test::TempDir dir;
    const fs::path a = make_scan(new_scan_folder(dir.path(), at(0ms)), 1);
    EXPECT_EQ(a.filename(), "scan-20261127-030000-250");
    const fs::path b = make_scan(new_scan_folder(dir.path(), at(1500ms)), 1);
    EXPECT_EQ(b.filename(), "scan-20261127-030001-750");
}

TEST(ScanStore, ClockJumpingBackKeepsNamesUniqueAndOrdered) {
    fpp::test::TempDir dir;
    std::vector<fs::path> made;
    made.reserve(5); // GCC 12 at -O3 on AArch64 misreads the growth of a vector of paths
    made.push_back(make_scan(new_scan_folder(dir.path(), at(0ms)), 10));
    made.push_back(make_scan(new_scan_folder(dir.path(), at(0ms)), 10));       // same millisecond
    made.push_back(make_scan(new_scan_folder(dir.path(), at(-hours(5))), 10)); // NTP step back
    made.push_back(make_scan(new_scan_folder(dir.path(), at(-hours(5) + 2s)), 10));
    made.push_back(make_scan(new_scan_folder(dir.path(), at(2s)), 10)); // caught up again
    EXPECT_EQ(made[1].filename(), "scan-20261127-030000-250-000002");
    EXPECT_EQ(made[2].filename(), "scan-20261127-030000-250-000003");
    EXPECT_EQ(made[3].filename(), "scan-20261127-030000-250-000004");
    EXPECT_EQ(made[4].filename(), "scan-20261127-030002-250");
    // In the order they were made, and the store's newest is the last made.
    EXPECT_EQ(list_scans(dir.path()), made);

    // Pruning removes the oldest made, never the ones after the jump.
    const auto removed = prune_store(dir.path(), 30, made.back());
    ASSERT_EQ(removed.size(), 2u);
    EXPECT_EQ(removed[0], made[0]);
    EXPECT_EQ(removed[1], made[1]);
}

TEST(ScanStore, SequenceOfTheNewestContinues) {
    fpp::test::TempDir dir;
    make_scan(dir / "scan-20261127-030000-250-000041", 1);
    EXPECT_EQ(new_scan_folder(dir.path(), at(-1s)).filename(), "scan-20261127-030000-250-000042");
    make_scan(dir / "scan-20261127-030000-250-999999", 1);
    EXPECT_THROW(new_scan_folder(dir.path(), at(-1s)), fpp::IoError);
}

// GET /scans sizes every scan folder while a DELETE or the store's pruning
// may remove one: a file that vanishes between the directory listing and its
// size counts as 0 bytes rather than failing the whole listing (Api.Load once
// answered 500 "cannot get file size" for a scan.json removed under it).
TEST(ScanStore, FolderBytesToleratesFilesRemovedWhileCounting) {
    fpp::test::TempDir dir;
    const fs::path folder = dir / "scan-20261127-030000-250";
    fs::create_directories(folder);
    std::atomic<bool> done{false};
    std::thread churn([&] {
        for (int i = 0; i < 4000; ++i) {
            static const char* const kNames[] = {"f0", "f1", "f2", "f3", "f4", "f5", "f6", "f7"};
            const fs::path file = folder / kNames[i % 8];
            std::ofstream(file) << "0123456789";
            std::error_code ec;
            fs::remove(file, ec);
        }
        done = true;
    });
    int counts = 0;
    std::uint64_t most = 0;
    while (!done) {
        std::uint64_t bytes = 0;
        EXPECT_NO_THROW(bytes = fpp::scanner::folder_bytes(folder));
        most = std::max(most, bytes);
        ++counts;
    }
    churn.join();
    EXPECT_GT(counts, 0);
    EXPECT_LE(most, 10u); // at most one 10-byte file exists at a time
    EXPECT_EQ(fpp::scanner::folder_bytes(folder), 0u);
    EXPECT_EQ(fpp::scanner::folder_bytes(dir / "no-such-scan"), 0u);
}

// The status counts the whole store while scans are written (a temporary
// folder renamed into place) and removed: a folder that vanishes between the
// listing and the descent into it counts as nothing (fuzz_http_api once had
// "cannot increment recursive directory iterator" escape GET /status).
TEST(ScanStore, FolderBytesToleratesFoldersRemovedWhileCounting) {
    fpp::test::TempDir dir;
    const fs::path store = dir / "store";
    fs::create_directories(store / "kept");
    std::ofstream(store / "kept" / "cloud.ply") << "01234";
    std::atomic<bool> done{false};
    std::thread churn([&] {
        for (int i = 0; i < 2000; ++i) {
            const fs::path scan = store / ("scan-" + std::to_string(i % 4));
            fs::create_directories(scan / "session" / "pose");
            std::ofstream(scan / "session" / "pose" / "frame.png") << "0123456789";
            std::error_code ec;
            fs::remove_all(scan, ec);
        }
        done = true;
    });
    int counts = 0;
    std::uint64_t least = 1000, most = 0;
    while (!done) {
        std::uint64_t bytes = 0;
        EXPECT_NO_THROW(bytes = fpp::scanner::folder_bytes(store));
        least = std::min(least, bytes);
        most = std::max(most, bytes);
        ++counts;
    }
    churn.join();
    EXPECT_GT(counts, 0);
    EXPECT_EQ(least, 5u);      // the kept file is always counted
    EXPECT_LE(most, 5u + 10u); // and at most one frame beside it
    EXPECT_EQ(fpp::scanner::folder_bytes(store), 5u);
}
