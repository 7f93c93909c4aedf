#pragma once
// A soak of the scanner as it runs in a cell: many scans on one process, the
// sim board's button and the HTTP API (a real socket on loopback) taking
// turns, the store pruned to a small limit. The scanner is the network
// daemon's own parts (NetworkedScanner: service, API, HTTP server) on a tiny
// virtual scanner (the paper rig with its effects, camera binned 16 x 16 to
// 100 x 75, projector 8 x 8 to 160 x 100, virtual clock), so that 10,000
// scans take minutes. Resident memory and open descriptors are sampled after
// every scan, once the scanner is idle again.
//
// Used by the benchmark (tests/bench/bench_soak.cpp, 10,000 scans) and by its
// short form in CI (tests/integration/scanner/test_scanner_soak.cpp). Header-only: it
// needs fpp_scanner and fpp_sim, which the support library does not link.
#include "fpp/coefficient_table.hpp"
#include "fpp/error.hpp"
#include "fpp/scanner/board_config.hpp"
#include "fpp/scanner/log.hpp"
#include "fpp/scanner/networked_scanner.hpp"
#include "fpp/scanner/scan_store.hpp"
#include "fpp/scanner/scanner.hpp"
#include "fpp/scanner/sim_board.hpp"
#include "fpp/simulator/rig.hpp"
#include "loopback_http.hpp"
#include "rig_truth_table.hpp"
#include "sim_board_yaml.hpp"
#include "test_support.hpp"
#include "tiny_rig.hpp"

#include <nlohmann/json.hpp>

#include <stdlib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <numeric>
#include <string>
#include <thread>
#include <vector>

namespace fpp::test {

struct SoakOptions {
    int scans = 10000;
    int warmup = 200;  // scans before the first window
    int window = 1000; // scans averaged at the start and at the end
    int store_max_mb = 1;
};

struct SoakFigures {
    int scans = 0;    // finished (written or failed)
    int failures = 0; // scans that failed, and requests refused
    int button_scans = 0;
    int api_scans = 0;
    std::string first_failure;
    double rss_first_kib = 0; // mean over the first window after the warm-up
    double rss_last_kib = 0;  // mean over the last window
    double fds_first = 0;     // the same for open descriptors
    double fds_last = 0;
    std::uint64_t store_bytes = 0; // what the store holds at the end
    std::uint64_t store_limit = 0;
    std::size_t store_scans = 0;
    std::vector<std::string> stray; // store entries that are not complete scans
    double seconds = 0;

    double rss_change() const { return (rss_last_kib - rss_first_kib) / rss_first_kib; }
    double fds_change() const { return (fds_last - fds_first) / fds_first; }
};

namespace soak_detail {

inline long rss_kib() {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("VmRSS:", 0) == 0)
            return std::stol(line.substr(6));
    return -1;
}

inline long open_fds() {
    long n = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator("/proc/self/fd"))
        ++n;
    return n;
}

inline double mean(const std::vector<long>& v, std::size_t from, std::size_t count) {
    return std::accumulate(v.begin() + static_cast<std::ptrdiff_t>(from),
                           v.begin() + static_cast<std::ptrdiff_t>(from + count), 0.0) /
           static_cast<double>(count);
}

// Entries of the store that are not a complete scan folder (a temporary
// file, a folder without its cloud or scan.json).
inline std::vector<std::string> stray_entries(const std::filesystem::path& store) {
    std::vector<std::string> stray;
    const auto scans = scanner::list_scans(store);
    for (const auto& e : std::filesystem::directory_iterator(store)) {
        const bool listed = std::find(scans.begin(), scans.end(), e.path()) != scans.end();
        if (e.path().filename() == "sessions")
            continue;
        if (!listed || !std::filesystem::exists(e.path() / "scan.json") ||
            !std::filesystem::exists(e.path() / "cloud.ply"))
            stray.push_back(e.path().filename().string());
        else
            for (const auto& f : std::filesystem::directory_iterator(e.path()))
                if (f.path().filename().string().rfind('.', 0) == 0)
                    stray.push_back(e.path().filename().string() + "/" +
                                    f.path().filename().string());
    }
    return stray;
}

} // namespace soak_detail

// Runs the soak in `dir` (the store on /dev/shm when there is one: every scan
// fsyncs, and durability is not what this measures).
inline SoakFigures run_soak(const SoakOptions& o, const std::filesystem::path& dir) {
    namespace fs = std::filesystem;
    using namespace std::chrono_literals;
    using namespace soak_detail;

    std::string shm = "/dev/shm/fpp-soak-XXXXXX";
    const bool on_shm = fs::is_directory("/dev/shm") && ::mkdtemp(shm.data()) != nullptr;
    const fs::path store = (on_shm ? fs::path(shm) : dir) / "scans";
    struct RemoveShm {
        bool on;
        fs::path path;
        ~RemoveShm() {
            std::error_code ec;
            if (on)
                fs::remove_all(path, ec);
        }
    } remove_shm{on_shm, shm};

    const std::string token = "0123456789abcdef0123456789abcdef";
    std::ofstream(dir / "token") << token << "\n";
    std::ofstream(dir / "rig.yaml") << sim::rig_to_yaml(tiny_rig());
    SimBoardYaml b;
    b.name = "soak-sim";
    b.store = store;
    b.rig = dir / "rig.yaml";
    b.table = "table.fpt";
    b.max_mb = o.store_max_mb;
    b.binning = 1;
    b.seed = 11;
    b.extra = "http: {listen: \"127.0.0.1:0\", token_file: " + (dir / "token").string() +
              ", max_connections: 16, timeout_s: 10}\n";
    std::ofstream(dir / "board.yaml") << b.text();
    scanner::BoardConfig board = scanner::read_board_config(dir / "board.yaml");
    scanner::SimBoard sim(board);
    sim.limit_records(scanner::SimBoard::kDaemonRecordLimit); // as fpp-scanner does
    write_table(dir / "table.fpt", rig_truth_table(sim.rig()));

    SoakFigures f;
    std::mutex failures_mutex;
    const scanner::Logger log([&](scanner::LogLevel level, const std::string& message) {
        if (level > scanner::LogLevel::error)
            return;
        const std::lock_guard lock(failures_mutex);
        if (f.first_failure.empty())
            f.first_failure = message;
    });
    scanner::Scanner scanner(board, sim.devices(), log);
    scanner::NetworkedScanner networked(
        board, scanner, sim.devices(), log,
        scanner::ServiceOptions{dir / "table.fpt", std::nullopt, "", true});
    const int port = networked.port();
    std::atomic<bool> stop{false};
    std::thread loop([&] { networked.run(scanner::ScanMode::scan, stop); });

    std::vector<long> rss, fds;
    rss.reserve(static_cast<std::size_t>(o.scans));
    fds.reserve(static_cast<std::size_t>(o.scans));
    const auto start = std::chrono::steady_clock::now();
    auto last_press = start - 1s;
    std::string last_id;
    for (int i = 0; i < o.scans; ++i) {
        if (i % 2 == 0) {
            // Presses closer than the board's debounce (30 ms) would be one.
            std::this_thread::sleep_until(last_press + 40ms);
            last_press = std::chrono::steady_clock::now();
            sim.button().press();
            ++f.button_scans;
        } else {
            const HttpReply r =
                http_request(port, "POST", "/api/v1/scans", token, R"({"mode":"scan"})");
            if (r.status != 202) {
                ++f.failures;
                const std::lock_guard lock(failures_mutex);
                if (f.first_failure.empty())
                    f.first_failure =
                        "POST /api/v1/scans: " + std::to_string(r.status) + " " + r.body;
                continue;
            }
            ++f.api_scans;
        }
        // Idle with a new last scan: this one ended (written or failed).
        const auto deadline = std::chrono::steady_clock::now() + 60s;
        for (;;) {
            const HttpReply r = http_request(port, "GET", "/api/v1/status", token);
            const auto status = nlohmann::json::parse(r.body, nullptr, false);
            if (r.status == 200 && !status.is_discarded() && status["state"] != "scanning" &&
                status["last_scan"].is_object() && status["last_scan"]["id"] != last_id) {
                last_id = status["last_scan"]["id"].get<std::string>();
                if (!status["last_scan"]["ok"].get<bool>())
                    ++f.failures;
                break;
            }
            if (std::chrono::steady_clock::now() > deadline) {
                ++f.failures;
                f.first_failure = f.first_failure.empty()
                                      ? "scan " + std::to_string(i) + " did not end within 60 s"
                                      : f.first_failure;
                break;
            }
            std::this_thread::sleep_for(1ms);
        }
        ++f.scans;
        rss.push_back(rss_kib());
        fds.push_back(open_fds());
    }
    f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stop = true;
    loop.join();

    const std::size_t n = rss.size();
    const auto window = static_cast<std::size_t>(o.window);
    const auto warmup = static_cast<std::size_t>(o.warmup);
    if (n >= warmup + 2 * window) {
        f.rss_first_kib = mean(rss, warmup, window);
        f.rss_last_kib = mean(rss, n - window, window);
        f.fds_first = mean(fds, warmup, window);
        f.fds_last = mean(fds, n - window, window);
    }
    const auto kept = scanner::list_scans(store);
    f.store_scans = kept.size();
    for (const auto& folder : kept)
        f.store_bytes += scanner::folder_bytes(folder);
    f.store_limit = board.store.max_bytes;
    f.stray = stray_entries(store);
    return f;
}

} // namespace fpp::test
