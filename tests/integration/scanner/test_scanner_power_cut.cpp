// Power cuts: fpp-scanner (the daemon, on a tiny virtual scanner, its store
// on disk) is killed with SIGKILL at random moments of 200 actions (kCuts), scans
// through the API and table installs, and started again each time. At every
// start the store must hold only complete scans (scan.json and a cloud that
// reads whole), the temporaries of cut writes must be gone once it listens,
// and the table must be the old or the new one, loaded, never a mix.
#include <gtest/gtest.h>

#include "fpp/coefficient_table.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/simulator/rig.hpp"
#include "loopback_http.hpp"
#include "rig_truth_table.hpp"
#include "sim_board_yaml.hpp"
#include "test_support.hpp"
#include "tiny_rig.hpp"

#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <random>
#include <signal.h>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

using fpp::test::file_bytes;

// The test runs under the sanitizers alone (tests/CMakeLists.txt), where a
// daemon start costs about 0.5 s: all 200 cuts there take about 40 s.
constexpr int kCuts = 200;
const std::string kToken = "0123456789abcdef0123456789abcdef";

// fpp-scanner --board FILE, its output in `log`, killed with SIGKILL.
class Daemon {
public:
    // `log` is removed first: a start must not read the last one's lines.
    Daemon(const fs::path& board, const fs::path& log) : log_(log) {
        fs::remove(log);
        const std::string board_arg = board.string(); // no allocation after fork()
        const std::string log_path = log.string();
        const std::string scanner = fpp::test::scanner_exe();
        pid_ = ::fork();
        if (pid_ == 0) {
            const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
            if (fd < 0 || ::dup2(fd, STDERR_FILENO) < 0 || ::dup2(fd, STDOUT_FILENO) < 0)
                _exit(127);
            ::execl(scanner.c_str(), scanner.c_str(), "--board", board_arg.c_str(),
                    static_cast<char*>(nullptr));
            _exit(127);
        }
    }
    ~Daemon() { kill(); }
    Daemon(const Daemon&) = delete;
    Daemon& operator=(const Daemon&) = delete;

    std::string log() const { return file_bytes(log_); }
    // The port once it listens (0 after 20 s, or when it exited).
    int wait_listening() {
        const std::string mark = "http: listening on 127.0.0.1:";
        for (int i = 0; i < 20000; ++i) {
            const std::string text = log();
            if (const std::size_t at = text.find(mark); at != std::string::npos)
                return std::stoi(text.substr(at + mark.size()));
            if (exited())
                return 0;
            std::this_thread::sleep_for(1ms);
        }
        return 0;
    }
    void kill() {
        if (pid_ <= 0)
            return;
        ::kill(pid_, SIGKILL);
        int status = 0;
        ::waitpid(pid_, &status, 0);
        pid_ = -1;
    }

private:
    bool exited() {
        int status = 0;
        if (::waitpid(pid_, &status, WNOHANG) == pid_) {
            pid_ = -1;
            return true;
        }
        return false;
    }
    fs::path log_;
    pid_t pid_ = -1;
};

// What is wrong with the store and the table at a start ("" when nothing).
std::string check_store(const fs::path& store, const fs::path& table_dir,
                        const std::vector<std::string>& tables, std::size_t& complete) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(store, ec)) {
        const std::string name = e.path().filename().string();
        if (name.starts_with("."))
            return "a temporary after the start: " + name;
        if (!name.starts_with("scan-"))
            return "not a scan: " + name;
        if (!fs::exists(e.path() / "scan.json"))
            return name + " has no scan.json";
        try {
            if (fpp::read_ply(e.path() / "cloud.ply").size() == 0)
                return name + "/cloud.ply has no points";
        } catch (const std::exception& x) {
            return name + "/cloud.ply: " + x.what();
        }
        ++complete;
    }
    for (const auto& e : fs::directory_iterator(table_dir))
        if (e.path().filename().string().starts_with(".table.fpt"))
            return "a table temporary after the start: " + e.path().filename().string();
    const std::string table = file_bytes(table_dir / "table.fpt");
    if (table != tables[0] && table != tables[1])
        return "table.fpt is neither the old nor the new table (" + std::to_string(table.size()) +
               " bytes)";
    return {};
}

} // namespace

TEST(ScannerPowerCut, KilledAtRandomMomentsTheStoreAndTableStayWhole) {
    fpp::test::TempDir dir;
    const fs::path store = dir / "scans";
    std::ofstream(dir / "token") << kToken << "\n";
    const fpp::sim::Rig rig = fpp::test::tiny_rig();
    std::ofstream(dir / "rig.yaml") << fpp::sim::rig_to_yaml(rig);
    // Two tables of the same size that differ in every model coefficient.
    fpp::sim::Rig moved = rig;
    moved.projector.cu += 0.25;
    std::vector<std::string> tables;
    for (const fpp::sim::Rig* r : {&rig, static_cast<const fpp::sim::Rig*>(&moved)}) {
        fpp::write_table(dir / "table.fpt", fpp::test::rig_truth_table(*r));
        tables.push_back(file_bytes(dir / "table.fpt"));
    }
    ASSERT_NE(tables[0], tables[1]);
    fpp::test::SimBoardYaml b;
    b.name = "power-cut-sim";
    b.store = store;
    b.rig = dir / "rig.yaml";
    b.table = "table.fpt";
    b.max_mb = 16;
    b.binning = 1;
    b.extra = "http: {listen: \"127.0.0.1:0\", token_file: " + (dir / "token").string() + "}\n";
    std::ofstream(dir / "board.yaml") << b.text();

    std::mt19937 random(17);
    // Each action's length, learnt from the ones that ended before their cut
    // and grown by each cut that came first: the cuts fall over 1.5 times of it.
    double scan_ms = 60, install_ms = 30;
    int cut_scans = 0, cut_installs = 0, starts_that_cleaned = 0;
    std::size_t complete = 0;
    for (int cycle = 0; cycle <= kCuts; ++cycle) {
        Daemon daemon(dir / "board.yaml", dir / "scanner.log");
        const int port = daemon.wait_listening();
        ASSERT_GT(port, 0) << "start " << cycle << ":\n" << daemon.log();
        std::size_t scans = 0;
        const std::string problem = check_store(store, dir.path(), tables, scans);
        ASSERT_EQ(problem, "") << "start " << cycle << ":\n" << daemon.log();
        complete = scans;
        const std::string log = daemon.log();
        starts_that_cleaned += log.find("left by writes cut short") != std::string::npos ? 1 : 0;
        const auto status = nlohmann::json::parse(
            fpp::test::http_request(port, "GET", "/api/v1/status", kToken).body);
        ASSERT_TRUE(status["table"].is_object()) << "start " << cycle << ": no table loaded\n"
                                                 << log;
        ASSERT_EQ(status["table"]["bytes"].get<std::size_t>(), fs::file_size(dir / "table.fpt"));
        if (cycle == kCuts)
            break;

        const bool install = cycle % 4 == 3;
        const double length_ms = install ? install_ms : scan_ms;
        const auto cut_after = std::chrono::microseconds(
            static_cast<long>(std::uniform_real_distribution<double>(0, 1500 * length_ms)(random)));
        const std::string current = file_bytes(dir / "table.fpt");
        const std::string& next = current == tables[0] ? tables[1] : tables[0];
        const auto started = std::chrono::steady_clock::now();
        std::atomic<bool> done{false};
        std::chrono::steady_clock::time_point ended; // read after join()
        std::thread action([&] {
            try {
                if (install) {
                    const int code =
                        fpp::test::http_request(port, "PUT", "/api/v1/table", kToken, next).status;
                    if (code / 100 != 2)
                        return; // cut before the answer (status 0)
                } else {
                    const auto posted =
                        nlohmann::json::parse(fpp::test::http_request(port, "POST", "/api/v1/scans",
                                                                      kToken, R"({"mode":"scan"})")
                                                  .body,
                                              nullptr, false);
                    if (posted.is_discarded() || !posted.contains("id"))
                        return; // cut before the answer
                    for (;;) {  // until it is written (the cut may come first)
                        const auto s = nlohmann::json::parse(
                            fpp::test::http_request(port, "GET", "/api/v1/status", kToken).body,
                            nullptr, false);
                        if (s.is_discarded())
                            return;
                        if (s["state"] != "scanning" && s["last_scan"].is_object() &&
                            s["last_scan"]["id"] == posted["id"])
                            break;
                        std::this_thread::sleep_for(1ms);
                    }
                }
                ended = std::chrono::steady_clock::now();
                done = true;
            } catch (const fpp::IoError&) { // the cut came first
            }
        });
        std::this_thread::sleep_until(started + cut_after);
        daemon.kill();
        action.join();
        if (done) { // ended before the cut: how long such an action takes
            const double took_ms =
                std::chrono::duration<double, std::milli>(ended - started).count();
            (install ? install_ms : scan_ms) = 0.8 * length_ms + 0.2 * took_ms;
        } else {
            ++(install ? cut_installs : cut_scans);
            // Cut first: it takes longer than that. The guess grows, so that
            // on a slow host (sanitizers, a loaded machine) some actions still
            // end; without this every scan was cut there and none was kept.
            (install ? install_ms : scan_ms) = 1.05 * length_ms;
        }
    }
    std::printf("%d cuts: %d scans and %d table installs cut in the middle; %d starts removed "
                "temporaries; %zu complete scans in the store; scan %.0f ms, install %.0f ms\n",
                kCuts, cut_scans, cut_installs, starts_that_cleaned, complete, scan_ms, install_ms);
    // The cuts must have hit writes in progress, or nothing was tested.
    EXPECT_GT(cut_scans, kCuts / 8);
    EXPECT_GT(cut_installs, kCuts / 40);
    EXPECT_GT(starts_that_cleaned, 0);
    EXPECT_GT(complete, 0u);
}
