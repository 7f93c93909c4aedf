#pragma once
// The scanner as its daemon runs it, in process: ScannerService on the sim
// test board (camera binned 4 x 4: 400 x 300, virtual clock), its table
// made from the rig's truth, the service loop on its own thread and its
// events followed from the start. For tests that drive the service and the
// sim board's devices (button, faults) together.
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <fpp/coefficient_table.hpp>
#include <fpp/scanner/api_events.hpp>
#include <fpp/scanner/board_config.hpp>
#include <fpp/scanner/event_hub.hpp>
#include <fpp/scanner/scanner.hpp>
#include <fpp/scanner/scanner_service.hpp>
#include <fpp/scanner/sim_board.hpp>

#include "rig_truth_table.hpp"
#include "sim_board_yaml.hpp"
#include "test_support.hpp"

namespace fpp::test {

// "event: NAME\ndata: JSON\n\n" -> NAME and JSON.
inline std::pair<std::string, std::string> parse_event(const std::string& text) {
    const std::size_t name_end = text.find('\n');
    const std::string name = text.substr(7, name_end - 7);
    const std::size_t data = text.find("data: ", name_end);
    return {name, text.substr(data + 6, text.find('\n', data) - data - 6)};
}

// The value of "id" in one line of JSON written by the service.
inline std::string id_of(const std::string& json) {
    const std::size_t at = json.find("\"id\":\"");
    if (at == std::string::npos)
        return {};
    return json.substr(at + 6, json.find('"', at + 6) - at - 6);
}

// The service's log kept for the test to read (lines come from the service's
// thread).
struct Journal {
    std::mutex mutex;
    std::vector<std::string> lines;
    scanner::Logger::Sink sink() {
        return [this](scanner::LogLevel, const std::string& m) {
            const std::lock_guard lock(mutex);
            lines.push_back(m);
        };
    }
    // Lines that contain `part`.
    int count(const std::string& part) {
        const std::lock_guard lock(mutex);
        int n = 0;
        for (const auto& line : lines)
            n += line.find(part) != std::string::npos ? 1 : 0;
        return n;
    }
};

// The test board (camera binned 4 x 4: 400 x 300, virtual clock) in `dir`,
// its table at dir/table.fpt, a store without pruning (a folder per scan stays).
inline scanner::BoardConfig sim_board_in(const std::filesystem::path& dir,
                                         const std::filesystem::path& store) {
    SimBoardYaml b;
    b.store = store;
    b.table = "table.fpt";
    b.max_mb = 4096;
    std::ofstream(dir / "board.yaml") << b.text();
    return scanner::read_board_config(dir / "board.yaml");
}

// The service on the test board, its table made from the rig's truth, run
// on its own thread, its events followed from the start; stopped and joined
// at the end.
struct RunningService {
    explicit RunningService(scanner::Logger::Sink sink = [](scanner::LogLevel,
                                                            const std::string&) {})
        : board(sim_board_in(dir.path(), dir / "scans")), sim(board), log(std::move(sink)) {
        write_table(dir / "table.fpt", rig_truth_table(sim.rig()));
        scanner.emplace(board, sim.devices(), log);
        service.emplace(board, *scanner, sim.devices(), rendered, log,
                        scanner::ServiceOptions{dir / "table.fpt", std::nullopt, "", true});
        stream = events.subscribe("");
        loop = std::thread([this] { service->run(scanner::ScanMode::scan, stop); });
    }
    ~RunningService() { stop_loop(); }
    RunningService(const RunningService&) = delete;
    RunningService& operator=(const RunningService&) = delete;

    void stop_loop() {
        stop = true;
        if (loop.joinable())
            loop.join();
    }
    std::filesystem::path store() const { return dir / "scans"; }

    TempDir dir;
    scanner::BoardConfig board;
    scanner::SimBoard sim;
    scanner::Logger log;
    std::optional<scanner::Scanner> scanner;
    scanner::EventHub events;
    scanner::ApiEvents rendered{events};            // the service's events as the API sends them
    std::optional<scanner::ScannerService> service; // after what it uses: destroyed first
    std::shared_ptr<scanner::EventHub::Subscription> stream;
    std::atomic<bool> stop{false};
    std::thread loop;
};

// The next event whose name is one of `names` ("written", "failed"), within
// `timeout`: {name, data}, or nullopt.
inline std::optional<std::pair<std::string, std::string>>
next_event(scanner::EventHub::Subscription& stream, std::initializer_list<std::string> names,
           std::chrono::seconds timeout = std::chrono::seconds(60)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
        const auto next = stream.next(std::chrono::milliseconds(100));
        if (!next || next->empty())
            continue;
        auto event = parse_event(*next);
        for (const auto& name : names)
            if (event.first == name)
                return event;
    }
    return std::nullopt;
}

} // namespace fpp::test
