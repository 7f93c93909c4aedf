// fpp-calib's scanner commands (scanner-session, scanner-pull,
// scanner-push-table, scanner-status) against the real fpp-scanner daemon
// serving its HTTP API on loopback (firmware/scanner/http-api.md), as a
// person runs them: a session recorded and pulled byte for byte, a table
// installed and a corrupt one refused with nothing changed, a wrong token,
// no scanner at all. The pieces underneath have their own tests:
// test_server_sent_events.cpp, test_session_archive.cpp.
#include "rig_truth_table.hpp"
#include "test_support.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/error.hpp"
#include "fpp/fnv1a.hpp"
#include "fpp/simulator/rig.hpp"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using fpp::test::run_tool;
using fpp::test::shell_quote;
using fpp::test::TempDir;
using Clock = std::chrono::steady_clock;

namespace {

using fpp::test::file_bytes;

constexpr const char* kToken = "fpp-test-token-0123456789abcdef";

void write_bytes(const fs::path& file, const std::string& bytes) {
    std::ofstream(file, std::ios::binary) << bytes;
}

std::string hex64(std::uint64_t value) {
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
    return text;
}

// fpp-scanner as a child process; its stdout and stderr read by a thread
// into log() (a daemon must never stall on a full pipe). SIGTERM and
// waitpid when the object goes, whether the test passed or not.
// The port of the daemon's "info: http: listening on 127.0.0.1:PORT" line
// ("" before it).
std::string listening_port(const std::string& log) {
    const std::string line = "info: http: listening on 127.0.0.1:";
    const std::size_t at = log.find(line);
    if (at == std::string::npos)
        return {};
    const std::size_t first = at + line.size();
    std::size_t end = first;
    while (end < log.size() && log[end] >= '0' && log[end] <= '9')
        ++end;
    // Digits at the end of what has been read may be a port cut short.
    return end > first && end < log.size() ? log.substr(first, end - first) : std::string();
}

class ScannerDaemon {
public:
    explicit ScannerDaemon(const std::vector<std::string>& args) {
        int pipe_fds[2];
        if (::pipe2(pipe_fds, O_CLOEXEC) != 0)
            throw std::runtime_error("pipe2 failed");
        std::vector<std::string> argv_text{fpp::test::scanner_exe()};
        argv_text.insert(argv_text.end(), args.begin(), args.end());
        std::vector<char*> argv;
        for (std::string& a : argv_text)
            argv.push_back(a.data());
        argv.push_back(nullptr);
        pid_ = ::fork();
        if (pid_ == 0) { // the child: only async-signal-safe calls until exec
            ::dup2(pipe_fds[1], STDOUT_FILENO);
            ::dup2(pipe_fds[1], STDERR_FILENO);
            ::execv(argv[0], argv.data());
            ::_exit(127);
        }
        ::close(pipe_fds[1]);
        if (pid_ < 0) {
            ::close(pipe_fds[0]);
            throw std::runtime_error("fork failed");
        }
        reader_ = std::thread([this, fd = pipe_fds[0]] { read_output(fd); });
        // With port 0 the daemon says which port it took.
        std::unique_lock lock(mutex_);
        std::string port;
        const bool found = changed_.wait_for(lock, std::chrono::seconds(30), [&] {
            port = listening_port(log_);
            return !port.empty() || output_closed_;
        });
        if (!found || port.empty()) {
            const std::string log = log_;
            lock.unlock();
            stop();
            throw std::runtime_error("fpp-scanner did not say where it listens within 30 s:\n" +
                                     log);
        }
        url_ = "http://127.0.0.1:" + port;
    }

    ~ScannerDaemon() { stop(); }
    ScannerDaemon(const ScannerDaemon&) = delete;
    ScannerDaemon& operator=(const ScannerDaemon&) = delete;

    const std::string& url() const { return url_; }
    std::string log() const {
        std::lock_guard lock(mutex_);
        return log_;
    }

    // SIGTERM, then waitpid (SIGKILL after 10 s); the exit status as
    // waitpid gives it (-1 when already stopped).
    int stop() {
        int status = -1;
        if (pid_ > 0) {
            ::kill(pid_, SIGTERM);
            const auto deadline = Clock::now() + std::chrono::seconds(10);
            while (::waitpid(pid_, &status, WNOHANG) == 0) {
                if (Clock::now() > deadline) {
                    ::kill(pid_, SIGKILL);
                    ::waitpid(pid_, &status, 0);
                    break;
                }
                std::this_thread::sleep_for(std::chrono::milliseconds(20));
            }
            pid_ = -1;
        }
        if (reader_.joinable())
            reader_.join();
        return status;
    }

private:
    void read_output(int fd) {
        char buffer[4096];
        for (;;) {
            const ssize_t n = ::read(fd, buffer, sizeof buffer);
            if (n < 0 && errno == EINTR)
                continue;
            std::lock_guard lock(mutex_);
            if (n <= 0) {
                output_closed_ = true;
                changed_.notify_all();
                break;
            }
            log_.append(buffer, static_cast<std::size_t>(n));
            changed_.notify_all();
        }
        ::close(fd);
    }

    pid_t pid_ = -1;
    std::string url_;
    std::thread reader_;
    mutable std::mutex mutex_;
    std::condition_variable changed_;
    std::string log_;
    bool output_closed_ = false;
};

// A scanner for the tests: board/sim-checkerboard-session.yaml as it is
// (800 x 600; the board moves on at every scan), its store, table path and
// token in a temporary folder.
struct ScannerSetup {
    TempDir dir;
    fs::path board = fpp::test::source_dir() / "board/sim-checkerboard-session.yaml";
    fs::path token = dir / "token";
    fs::path store = dir / "store";
    fs::path table = dir / "installed.fpt"; // where the scanner installs tables

    ScannerSetup() { write_bytes(token, std::string(kToken) + "\n"); }

    std::vector<std::string> daemon_args() const {
        return {"--board",      board.string(), "--http",  "127.0.0.1:0",
                "--token-file", token.string(), "--store", store.string(),
                "--table",      table.string(), "--mode",  "capture"};
    }

    // fpp-calib with `args`, `environment` (NAME=value ...) added to its
    // environment.
    fpp::test::ToolRun calib(const std::string& args, const std::string& environment = "") const {
        // Loopback needs no proxy; a proxy from the environment must not
        // get the requests (nor the token).
        return run_tool("env",
                        "-u http_proxy -u HTTP_PROXY -u all_proxy -u ALL_PROXY -u FPP_SCANNER "
                        "-u FPP_SCANNER_TOKEN " +
                            environment + " " + shell_quote(fpp::test::calib_exe()) + " " + args,
                        dir.path());
    }
    std::string connection(const ScannerDaemon& scanner) const {
        return " --scanner " + scanner.url() + " --token-file " + shell_quote(token);
    }
};

// Every file below `root`, by relative path, with its bytes.
std::map<std::string, std::string> tree(const fs::path& root) {
    std::map<std::string, std::string> files;
    for (const auto& item : fs::recursive_directory_iterator(root))
        if (item.is_regular_file())
            files[fs::relative(item.path(), root).string()] = file_bytes(item.path());
    return files;
}

// Empty when both trees hold the same files with the same bytes; otherwise
// the first difference.
std::string tree_difference(const fs::path& a, const fs::path& b) {
    const auto ta = tree(a), tb = tree(b);
    for (const auto& [name, bytes] : ta) {
        const auto it = tb.find(name);
        if (it == tb.end())
            return name + " is in " + a.string() + " only";
        if (it->second != bytes)
            return name + " differs";
    }
    for (const auto& [name, bytes] : tb)
        if (!ta.count(name))
            return name + " is in " + b.string() + " only";
    return "";
}

// Names in `folder` starting with '.': what a failed pull must not leave.
std::vector<std::string> hidden_entries(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& item : fs::directory_iterator(folder))
        if (item.path().filename().string().front() == '.')
            names.push_back(item.path().filename().string());
    return names;
}

} // namespace

TEST(ScannerNetwork, SessionRecordedOverHttpIsPulledByteForByte) {
    ScannerSetup setup;
    ScannerDaemon scanner(setup.daemon_args());
    const auto started = Clock::now();
    const fs::path pulled = setup.dir / "pulled";
    const auto session =
        setup.calib("scanner-session" + setup.connection(scanner) +
                    " --name cal-1 --poses 3 --no-wait --out " + shell_quote(pulled));
    const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
    ASSERT_EQ(session.exit_code, 0) << session.output << "\nscanner:\n" << scanner.log();
    std::printf("scanner-session, 3 poses at 800 x 600 over HTTP: %.1f s\n", seconds);
    EXPECT_NE(session.output.find("session cal-1: 3 poses"), std::string::npos) << session.output;
    EXPECT_NE(session.output.find("pose 3 of 3: written as scan-"), std::string::npos)
        << session.output;

    // The folder is the store's session folder, byte for byte.
    const fs::path in_store = setup.store / "sessions" / "cal-1";
    ASSERT_TRUE(fs::is_directory(in_store)) << "no " << in_store << "\n" << scanner.log();
    EXPECT_EQ(tree_difference(in_store, pulled), "");
    // ...and a session folder for `calibrate`: board.yaml, and per pose its
    // scan.json and a capture set that reads back.
    EXPECT_TRUE(fs::is_regular_file(pulled / "board.yaml"));
    int poses = 0;
    for (const auto& item : fs::directory_iterator(pulled)) {
        if (!item.is_directory())
            continue;
        ++poses;
        EXPECT_TRUE(fs::is_regular_file(item.path() / "scan.json")) << item.path();
        const fpp::CaptureSet set = fpp::read_capture_set(item.path() / "capture");
        EXPECT_EQ(set.frames.size(), set.manifest.frames.size()) << item.path();
        EXPECT_GT(set.frames.size(), 20u) << item.path(); // gray-xy
    }
    EXPECT_EQ(poses, 3);
    EXPECT_EQ(hidden_entries(setup.dir.path()), std::vector<std::string>{});

    // scanner-pull gives the same folder again, and never writes over one.
    const fs::path again = setup.dir / "again";
    const auto pull = setup.calib("scanner-pull" + setup.connection(scanner) +
                                  " --session cal-1 --out " + shell_quote(again));
    ASSERT_EQ(pull.exit_code, 0) << pull.output;
    EXPECT_EQ(tree_difference(in_store, again), "");
    const auto over = setup.calib("scanner-pull" + setup.connection(scanner) +
                                  " --session cal-1 --out " + shell_quote(again));
    EXPECT_NE(over.exit_code, 0);
    EXPECT_NE(over.output.find("already exists"), std::string::npos) << over.output;

    // A session the scanner does not have: its 404 named, nothing written.
    const fs::path none = setup.dir / "none";
    const auto missing = setup.calib("scanner-pull" + setup.connection(scanner) +
                                     " --session no-such-session --out " + shell_quote(none));
    EXPECT_NE(missing.exit_code, 0);
    EXPECT_NE(missing.output.find("HTTP 404"), std::string::npos) << missing.output;
    EXPECT_NE(missing.output.find(scanner.url() + "/api/v1/sessions/no-such-session/session.tar"),
              std::string::npos)
        << missing.output;
    EXPECT_FALSE(fs::exists(none));
    EXPECT_EQ(hidden_entries(setup.dir.path()), std::vector<std::string>{});

    // The same name twice: the scanner's 409, before any pose is taken.
    const auto twice =
        setup.calib("scanner-session" + setup.connection(scanner) +
                    " --name cal-1 --poses 1 --no-wait --out " + shell_quote(setup.dir / "twice"));
    EXPECT_NE(twice.exit_code, 0);
    EXPECT_NE(twice.output.find("HTTP 409"), std::string::npos) << twice.output;
    EXPECT_FALSE(fs::exists(setup.dir / "twice"));

    // SIGTERM ends the daemon cleanly, clients and all.
    const int status = scanner.stop();
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status << "\n" << scanner.log();
}

// --check: the session so far checked after each pose from the third;
// enough (a loose target here) ends the session there.
TEST(ScannerNetwork, SessionCheckedAfterEachPoseEndsWhenEnough) {
    ScannerSetup setup;
    ScannerDaemon scanner(setup.daemon_args());
    const fs::path pulled = setup.dir / "pulled";
    const auto session = setup.calib("scanner-session" + setup.connection(scanner) +
                                     " --name cal-2 --poses 6 --no-wait --check --target-um "
                                     "100000 --out " +
                                     shell_quote(pulled));
    ASSERT_EQ(session.exit_code, 0) << session.output << "\nscanner:\n" << scanner.log();
    EXPECT_NE(session.output.find("after pose 3: Session: enough"), std::string::npos)
        << session.output;
    EXPECT_NE(session.output.find("Predicted trueness"), std::string::npos) << session.output;
    EXPECT_NE(session.output.find("the session is enough after 3 poses"), std::string::npos)
        << session.output;
    EXPECT_EQ(session.output.find("pose 4 of 6"), std::string::npos) << session.output;
    int poses = 0;
    for (const auto& item : fs::directory_iterator(pulled))
        poses += item.is_directory();
    EXPECT_EQ(poses, 3);
    // The checks' own pulls leave nothing behind.
    EXPECT_FALSE(fs::exists(setup.dir / "pulled.check"));
    EXPECT_EQ(hidden_entries(setup.dir.path()), std::vector<std::string>{});
    const auto bad = setup.calib("scanner-session" + setup.connection(scanner) +
                                 " --name cal-3 --poses 3 --no-wait --check --target-um 0 --out " +
                                 shell_quote(setup.dir / "bad"));
    EXPECT_NE(bad.exit_code, 0);
    EXPECT_NE(bad.output.find("--target-um"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(setup.dir / "bad"));
}

TEST(ScannerNetwork, PushedTableIsInstalledAndACorruptOneChangesNothing) {
    ScannerSetup setup;
    // The sim rig's true table for the board's camera (binned 2 x 2).
    const fs::path good = setup.dir / "good.fpt";
    fpp::write_table(good, fpp::test::rig_truth_table(
                               fpp::sim::load_rig(fpp::sim::effects_rig_path()).binned_camera(2)));
    const std::string good_bytes = file_bytes(good);
    const std::string good_hash = hex64(fpp::fnv1a64(good_bytes.data(), good_bytes.size()));

    ScannerDaemon scanner(setup.daemon_args());
    const auto push =
        setup.calib("scanner-push-table" + setup.connection(scanner) + " " + shell_quote(good));
    ASSERT_EQ(push.exit_code, 0) << push.output << "\nscanner:\n" << scanner.log();
    EXPECT_NE(push.output.find("file_fnv1a64 " + good_hash), std::string::npos) << push.output;
    EXPECT_NE(push.output.find("model rational"), std::string::npos) << push.output;
    const auto status = setup.calib("scanner-status" + setup.connection(scanner));
    ASSERT_EQ(status.exit_code, 0) << status.output;
    EXPECT_NE(status.output.find("\"file_fnv1a64\": \"" + good_hash + "\""), std::string::npos)
        << status.output;
    EXPECT_EQ(file_bytes(setup.table), good_bytes);

    // Truncated: the scanner's loader refuses it, naming the field its
    // strict loader names here too, and the table in use stays.
    const fs::path cut = setup.dir / "cut.fpt";
    write_bytes(cut, good_bytes.substr(0, good_bytes.size() / 2));
    std::string field;
    try {
        fpp::load_table(cut);
    } catch (const fpp::InputError& e) {
        field = e.field();
    }
    ASSERT_FALSE(field.empty());
    const auto refused =
        setup.calib("scanner-push-table" + setup.connection(scanner) + " " + shell_quote(cut));
    EXPECT_NE(refused.exit_code, 0) << refused.output;
    EXPECT_NE(refused.output.find("HTTP 400"), std::string::npos) << refused.output;
    EXPECT_NE(refused.output.find(field), std::string::npos) << field << "\n" << refused.output;
    const auto after = setup.calib("scanner-status" + setup.connection(scanner));
    ASSERT_EQ(after.exit_code, 0) << after.output;
    EXPECT_NE(after.output.find("\"file_fnv1a64\": \"" + good_hash + "\""), std::string::npos)
        << after.output;
    EXPECT_EQ(file_bytes(setup.table), good_bytes);
}

TEST(ScannerNetwork, WrongTokenIsRefusedWith401) {
    ScannerSetup setup;
    ScannerDaemon scanner(setup.daemon_args());
    write_bytes(setup.dir / "wrong", "not-the-scanner-token-0123456789\n");
    const std::string wrong =
        " --scanner " + scanner.url() + " --token-file " + shell_quote(setup.dir / "wrong");
    const auto status = setup.calib("scanner-status" + wrong);
    EXPECT_NE(status.exit_code, 0);
    EXPECT_NE(status.output.find("HTTP 401"), std::string::npos) << status.output;
    EXPECT_NE(status.output.find(scanner.url() + "/api/v1/status"), std::string::npos)
        << status.output;
    const auto pull = setup.calib("scanner-pull" + wrong + " --session cal-1 --out " +
                                  shell_quote(setup.dir / "pulled"));
    EXPECT_NE(pull.exit_code, 0);
    EXPECT_NE(pull.output.find("HTTP 401"), std::string::npos) << pull.output;
    EXPECT_FALSE(fs::exists(setup.dir / "pulled"));
    // The scanner and its token from the environment instead: the right
    // token passes, a wrong one does not.
    const std::string url = shell_quote("FPP_SCANNER=" + scanner.url());
    const auto from_env =
        setup.calib("scanner-status", url + " FPP_SCANNER_TOKEN=" + std::string(kToken));
    EXPECT_EQ(from_env.exit_code, 0) << from_env.output;
    EXPECT_NE(from_env.output.find("\"api\": 1"), std::string::npos) << from_env.output;
    const auto wrong_env =
        setup.calib("scanner-status", url + " FPP_SCANNER_TOKEN=not-the-scanner-token-0123456789");
    EXPECT_NE(wrong_env.exit_code, 0);
    EXPECT_NE(wrong_env.output.find("HTTP 401"), std::string::npos) << wrong_env.output;
}

TEST(ScannerNetwork, AbsentScannerIsAClearErrorAtOnce) {
    ScannerSetup setup;
    // A port bound but not listening: connections to it are refused.
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    ASSERT_GE(fd, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
    socklen_t length = sizeof address;
    ASSERT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length), 0);
    const std::string url = "http://127.0.0.1:" + std::to_string(ntohs(address.sin_port));

    const auto started = Clock::now();
    const auto status = setup.calib("scanner-status --scanner " + url + " --token-file " +
                                    shell_quote(setup.token));
    const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
    ::close(fd);
    EXPECT_NE(status.exit_code, 0);
    EXPECT_NE(status.output.find(url + "/api/v1/status"), std::string::npos) << status.output;
    EXPECT_NE(status.output.find("is fpp-scanner running there"), std::string::npos)
        << status.output;
    EXPECT_LT(seconds, 5.0);
    // Nothing is asked of an absent scanner before the output folder is
    // known to be free; and nothing is left behind.
    const auto session = setup.calib("scanner-session --scanner " + url + " --token-file " +
                                     shell_quote(setup.token) + " --name x --no-wait --out " +
                                     shell_quote(setup.dir / "s"));
    EXPECT_NE(session.exit_code, 0);
    EXPECT_FALSE(fs::exists(setup.dir / "s"));
}
