// ScannerService (the scanner as a network device) on the virtual scanner:
// the button and the API share one scan at a time. The HTTP tests in
// tests/api cannot press the sim board's button from outside the daemon, so
// the race between a press and a POST /scans is driven here, in process.
#include <gtest/gtest.h>

#include "fpp/coefficient_table.hpp"
#include "fpp/scanner/api_error.hpp"
#include "fpp/scanner/board_config.hpp"
#include "fpp/scanner/event_hub.hpp"
#include "fpp/scanner/scan_store.hpp"
#include "fpp/scanner/scanner.hpp"
#include "fpp/scanner/scanner_service.hpp"
#include "fpp/scanner/sim_board.hpp"
#include "running_service.hpp"
#include "test_support.hpp"

#include <algorithm>
#include <atomic>
#include <barrier>
#include <chrono>
#include <fstream>
#include <iterator>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using namespace fpp;
using namespace fpp::scanner;
using fpp::test::id_of;
using fpp::test::parse_event;
using fpp::test::RunningService;

TEST(ScannerService, ButtonAndApiAtTheSameMomentStartOneScan) {
    fpp::test::Journal journal;
    RunningService rs(journal.sink());

    ScannerService& service = *rs.service;
    SimBoard& sim = rs.sim;
    const auto& stream = rs.stream;
    const fs::path store = rs.store();

    // Every event, in order, read by one thread: scans must never overlap.
    std::vector<std::pair<std::string, std::string>> seen;
    std::mutex seen_mutex;
    std::atomic<bool> reading{true};
    std::thread reader([&] {
        while (reading.load()) {
            const auto next = stream->next(std::chrono::milliseconds(20));
            if (!next)
                return;
            if (next->empty())
                continue;
            const std::lock_guard lock(seen_mutex);
            seen.push_back(parse_event(*next));
        }
    });
    const auto written_count = [&] {
        const std::lock_guard lock(seen_mutex);
        int n = 0;
        for (const auto& [name, data] : seen)
            n += name == "written" || name == "failed" ? 1 : 0;
        return n;
    };

    // Both at the same moment, and around it: the request up to 1 ms after
    // the press (the button's scan needs the scanning thread to wake) or
    // before it, so that either side wins some rounds.
    constexpr int kRounds = 20;
    constexpr int kApiDelayUs[] = {0, 0, 100, 300, 1000, 0, -100, 200, 600, 0};
    int api_won = 0, refused = 0;
    std::set<std::string> api_ids;
    for (int round = 0; round < kRounds; ++round) {
        const int delay_us = kApiDelayUs[round % std::size(kApiDelayUs)];
        std::barrier together(2);
        std::string id;
        int status = 0;
        std::thread api([&] {
            together.arrive_and_wait();
            if (delay_us > 0)
                std::this_thread::sleep_for(std::chrono::microseconds(delay_us));
            try {
                id = service.start_scan(ScanMode::scan);
            } catch (const ApiError& e) {
                status = e.status();
            }
        });
        together.arrive_and_wait();
        if (delay_us < 0)
            std::this_thread::sleep_for(std::chrono::microseconds(-delay_us));
        sim.button().press();
        api.join();
        if (id.empty()) {
            EXPECT_EQ(status, 409) << "round " << round;
            ++refused;
        } else {
            ++api_won;
            api_ids.insert(id);
        }
        // This round's scan ends; then nothing else may start from it.
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
        while (written_count() < round + 1 && std::chrono::steady_clock::now() < deadline)
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        ASSERT_EQ(written_count(), round + 1) << "round " << round << ": no scan ended";
        std::this_thread::sleep_for(std::chrono::milliseconds(150));
        ASSERT_EQ(written_count(), round + 1) << "round " << round << ": a second scan ran";
        EXPECT_EQ(list_scans(store).size(), static_cast<std::size_t>(round + 1))
            << "round " << round;
    }
    rs.stop_loop();
    reading = false;
    reader.join();

    std::printf("%d rounds: the API's request won %d, the button won %d (409 to the API)\n",
                kRounds, api_won, refused);
    EXPECT_EQ(api_won + refused, kRounds);
    // The loser is refused (409) or its press logged as ignored, every round.
    EXPECT_EQ(journal.count("button pressed while a scan is queued: ignored") +
                  journal.count("during the scan: ignored"),
              api_won);
    EXPECT_EQ(service.status().scans_completed, kRounds);
    EXPECT_EQ(list_scans(store).size(), static_cast<std::size_t>(kRounds));

    // Events: started, frames, decoded, written; never a start inside a scan.
    std::string running;
    int started = 0, api_started = 0;
    std::vector<std::string> ids;
    for (const auto& [name, data] : seen) {
        if (name == "scan-started") {
            EXPECT_TRUE(running.empty()) << "a scan started while " << running << " ran";
            running = id_of(data);
            ids.push_back(running);
            ++started;
            if (data.find("\"source\":\"api\"") != std::string::npos) {
                ++api_started;
                EXPECT_TRUE(api_ids.count(running)) << running;
            }
        } else if (name == "written" || name == "failed") {
            EXPECT_EQ(name, "written") << data;
            EXPECT_EQ(id_of(data), running);
            running.clear();
        } else if (name == "frame-captured" || name == "decoded") {
            EXPECT_EQ(id_of(data), running) << name;
        }
    }
    EXPECT_EQ(started, kRounds);
    EXPECT_EQ(api_started, api_won);
    // One folder per round, each the one its scan announced.
    const auto folders = list_scans(store);
    ASSERT_EQ(folders.size(), ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i)
        EXPECT_EQ(folders[i].filename().string(), ids[i]);
}

// `written` (and the idle state after it) say the scanner takes the next
// request: a client that starts a scan the moment it reads the event (the
// page, fpp-calib's session recorder) must not be refused as busy.
TEST(ScannerService, ScanRequestedOnWrittenIsTaken) {
    RunningService rs;
    ScannerService& service = *rs.service;
    const auto& stream = rs.stream;
    const fs::path store = rs.store();

    constexpr int kScans = 15;
    int refused = 0;
    service.start_scan(ScanMode::scan);
    for (int k = 1; k < kScans; ++k) {
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
        for (;;) {
            const auto next = stream->next(std::chrono::milliseconds(100));
            ASSERT_TRUE(next.has_value());
            if (next->starts_with("event: written"))
                break;
            ASSERT_FALSE(next->starts_with("event: failed")) << *next;
            ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "scan " << k;
        }
        try {
            service.start_scan(ScanMode::scan); // at once, as the event is read
        } catch (const ApiError& e) {
            ++refused;
            ADD_FAILURE() << "scan " << k << " refused right after written: " << e.status() << " "
                          << e.what();
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
            service.start_scan(ScanMode::scan);
        }
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (service.status().scans_completed < kScans && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    rs.stop_loop();
    EXPECT_EQ(refused, 0);
    EXPECT_EQ(service.status().scans_completed, kScans);
    EXPECT_EQ(list_scans(store).size(), static_cast<std::size_t>(kScans));
}

// A scan that fails (the camera gone mid-scan, after its one retry) is
// reported to every client: a `failed` event with the reason, then the
// error state with it, the last scan marked failed, nothing in the store.
TEST(ScannerService, FailedScanIsReportedWithItsReason) {
    RunningService rs;
    ScannerService& service = *rs.service;
    SimBoard& sim = rs.sim;
    const auto& stream = rs.stream;
    const fs::path store = rs.store();

    sim.camera().inject_fault(sim::CameraFault::gone, 5);
    const std::string id = service.start_scan(ScanMode::scan);
    std::vector<std::pair<std::string, std::string>> seen;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline) {
        const auto next = stream->next(std::chrono::milliseconds(100));
        ASSERT_TRUE(next.has_value());
        if (next->empty())
            continue;
        seen.push_back(parse_event(*next));
        if (seen.back().first == "state" &&
            seen.back().second.find("\"state\":\"error\"") != std::string::npos)
            break;
    }
    rs.stop_loop();

    std::vector<std::string> names;
    for (const auto& [name, data] : seen)
        names.push_back(name);
    const auto failed = std::find(names.begin(), names.end(), "failed");
    ASSERT_NE(failed, names.end());
    const std::string& data = seen[static_cast<std::size_t>(failed - names.begin())].second;
    EXPECT_EQ(id_of(data), id);
    EXPECT_NE(data.find("camera"), std::string::npos) << data;
    EXPECT_EQ(std::count(names.begin(), names.end(), "written"), 0);
    EXPECT_EQ(names.back(), "state"); // the error state comes after the event
    const ScannerStatus status = service.status();
    EXPECT_EQ(status.state.state, ScannerState::error);
    EXPECT_NE(status.state.error.find("camera"), std::string::npos);
    ASSERT_TRUE(status.last_scan);
    EXPECT_EQ(status.last_scan->id, id);
    EXPECT_FALSE(status.last_scan->ok);
    EXPECT_TRUE(list_scans(store).empty());
    EXPECT_EQ(sim.led().state(), drivers::LedState::error);
}
