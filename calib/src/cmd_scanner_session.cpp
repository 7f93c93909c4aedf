// fpp-calib scanner-session --scanner URL --token-file FILE --name NAME --out DIR
//                           [--poses N] [--board-yaml FILE] [--no-wait] [--pose-timeout S]
//                           [--response] [--check [--target-um UM]]
//
// Records a calibration session on a scanner over its HTTP API, one
// capture-mode scan per pose (with --response, first the projector's
// response ramp at the first pose), then pulls it as a session folder for
// `calibrate`. With --check, the session so far is checked after each pose
// from the third (session-check: the trueness so far and the next pose in
// words), and the session ends as soon as it is enough.

#include "cli_util.hpp"
#include "commands.hpp"
#include "scanner_connection.hpp"
#include "scanner_pull.hpp"
#include "session_check_run.hpp"

#include "fpp/yaml_fields.hpp"

#include <unistd.h>

#include <iostream>
#include <memory>

namespace fpp::calib {

namespace {
struct ScannerSessionArgs {
    ScannerConnectionArgs connection;
    std::string name;
    std::string out;
    std::string board_yaml;
    int poses = 30;
    bool no_wait = false;
    bool response = false;
    double pose_timeout_s = 600;
    bool check = false;
    double target_um = 15;
};

// The session so far, pulled beside `out` and checked as session-check
// checks it (the whole session again each time: corners are found anew).
SessionVerdict check_so_far(const ScannerClient& client, const ScannerSessionArgs& args,
                            const std::filesystem::path& out, int pose) {
    const std::filesystem::path probe = out.string() + ".check";
    std::filesystem::remove_all(probe);
    pull_scanner_session(client, args.name, probe);
    SessionCheckOptions options;
    options.target_mm = args.target_um / 1000;
    SessionCheck check;
    try {
        check = check_session_folder(probe, options, 0, {});
    } catch (...) {
        std::filesystem::remove_all(probe);
        throw;
    }
    std::filesystem::remove_all(probe);
    std::cout << "after pose " << pose << ": " << check.text() << std::flush;
    return check.verdict;
}

// Progress of one pose on stderr: one line updated in place on a terminal,
// a line at its start and one at its end otherwise.
class PoseProgress {
public:
    PoseProgress(int index, int count)
        : prefix_("pose " + std::to_string(index) + " of " + std::to_string(count) + ": "),
          terminal_(::isatty(STDERR_FILENO) == 1) {}

    void started(const std::string& id, int frames) {
        std::cerr << prefix_ << "scanning " << id << " (" << frames << " frames)"
                  << (terminal_ ? "" : "\n") << std::flush;
    }
    void frame(int frame, int frames) {
        if (terminal_)
            std::cerr << "\r\033[K" << prefix_ << "frame " << frame << " of " << frames
                      << std::flush;
    }
    void finished(const std::string& what) {
        std::cerr << (terminal_ ? "\r\033[K" : "") << prefix_ << what << " in "
                  << seconds_text(watch_.seconds()) << "\n";
    }

private:
    std::string prefix_;
    bool terminal_;
    Stopwatch watch_;
};

int int_field(const nlohmann::json& data, const char* key) {
    const auto it = data.find(key);
    return it != data.end() && it->is_number_integer() ? it->get<int>() : 0;
}

std::string text_field(const nlohmann::json& data, const char* key) {
    const auto it = data.find(key);
    if (it == data.end())
        return "";
    return it->is_string() ? it->get<std::string>() : it->dump();
}

// One pose: a capture-mode scan into the session, followed on the event
// stream until it is written (returns its id) or fails (throws).
std::string record_pose(const ScannerClient& client, const ScannerSessionArgs& args, int index) {
    // The stream is opened and its first event (the state, sent on
    // connecting) awaited before the scan is asked for, so that none of the
    // scan's events can go by unseen.
    ScannerEventStream events = client.events();
    for (;;) {
        const auto first = events.next(std::chrono::seconds(10));
        if (!first)
            throw ScannerError("GET " + client.url("/api/v1/events") +
                               ": no `state` event within 10 s of connecting");
        if (first->name == "state")
            break;
    }
    const nlohmann::json answer =
        client.post_json("/api/v1/sessions/" + args.name + "/poses", nullptr);
    const std::string id = text_field(answer, "id");
    if (id.empty())
        throw ScannerError("POST " + client.url("/api/v1/sessions/" + args.name + "/poses") +
                           ": the answer names no scan id: " + answer.dump());

    PoseProgress progress(index, args.poses);
    const auto timeout = std::chrono::duration<double>(args.pose_timeout_s);
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        const auto event = left.count() > 0 ? events.next(left) : std::nullopt;
        if (!event)
            throw ScannerError("pose " + std::to_string(index) + " (" + id + "): not written " +
                               "within " + std::to_string(int(args.pose_timeout_s)) +
                               " s (--pose-timeout)");
        const auto data = nlohmann::json::parse(event->data, nullptr, false);
        if (!data.is_object() || text_field(data, "id") != id)
            continue; // another scan's event, or the state
        if (event->name == "scan-started") {
            progress.started(id, int_field(data, "frames"));
        } else if (event->name == "frame-captured") {
            progress.frame(int_field(data, "frame"), int_field(data, "frames"));
        } else if (event->name == "written") {
            progress.finished("written as " + id);
            return id;
        } else if (event->name == "failed") {
            progress.finished("failed");
            throw ScannerError("pose " + std::to_string(index) + " (" + id +
                               "): the scan failed: " + text_field(data, "error") +
                               "; the poses written before it stay in session " + args.name +
                               " on the scanner (fpp-calib scanner-pull fetches them)");
        }
    }
}

int run_scanner_session(const ScannerSessionArgs& args) {
    check_session_name(args.name);
    const std::filesystem::path out = new_output_folder(args.out);
    if (args.poses < 1)
        throw std::invalid_argument("--poses: at least 1");
    if (args.pose_timeout_s <= 0)
        throw std::invalid_argument("--pose-timeout: more than 0 s");
    if (!(args.target_um > 0))
        throw std::invalid_argument("--target-um: more than 0");
    nlohmann::json request = {{"name", args.name}};
    if (!args.board_yaml.empty())
        request["board_yaml"] = yaml_fields::read_text_file(args.board_yaml);

    const ScannerClient client = connect_to_scanner(args.connection);
    client.post_json("/api/v1/sessions", request);
    std::cerr << "session " << args.name << " created on " << client.base_url() << "\n";
    for (int pose = 1; pose <= args.poses; ++pose) {
        if (!args.no_wait) {
            std::cerr << "pose " << pose << " of " << args.poses
                      << ": place the board, then press Enter " << std::flush;
            std::string line;
            const bool typed = ::isatty(STDIN_FILENO) == 1; // echoed its own newline
            const bool got = static_cast<bool>(std::getline(std::cin, line));
            if (!typed)
                std::cerr << "\n";
            if (!got)
                throw std::runtime_error("standard input ended before pose " +
                                         std::to_string(pose) +
                                         " (--no-wait scans without "
                                         "waiting); the poses so far stay in session " +
                                         args.name + " on the scanner");
        }
        if (pose == 1 && args.response) {
            const nlohmann::json ramp =
                client.post_json("/api/v1/sessions/" + args.name + "/response", nullptr);
            std::cerr << "projector response ramp recorded: " << int_field(ramp, "frames")
                      << " grey levels\n";
        }
        record_pose(client, args, pose);
        if (args.check && pose >= 3 &&
            check_so_far(client, args, out, pose) == SessionVerdict::enough) {
            std::cerr << "the session is enough after " << pose << " poses\n";
            break;
        }
    }
    pull_scanner_session(client, args.name, out);
    std::cout << "next: fpp-calib calibrate " << out.string()
              << " --out calib.yaml --table table.fpt, then fpp-calib scanner-push-table "
                 "table.fpt\n";
    return 0;
}
} // namespace

Action add_scanner_session_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<ScannerSessionArgs>(
        app, "scanner-session",
        "Record a calibration session on a scanner over its HTTP API (one capture-mode scan "
        "per pose, each after Enter is pressed, the board placed), then download it as a "
        "session folder for `calibrate`, as scanner-pull does",
        run_scanner_session);
    add_scanner_connection_options(*cmd, args->connection);
    cmd->add_option("--name", args->name,
                    "the session's name on the scanner (1 to 64 of A-Z a-z 0-9 . _ -)")
        ->required();
    cmd->add_option("--out", args->out, "the session folder to create (must not exist)")
        ->required();
    cmd->add_option("--poses", args->poses, "number of poses")->capture_default_str();
    cmd->add_option("--board-yaml", args->board_yaml,
                    "the calibration board's description (fpp-board/1); a simulated session "
                    "board gives its own")
        ->check(CLI::ExistingFile);
    cmd->add_flag("--no-wait", args->no_wait,
                  "scan the poses back to back without waiting for Enter (a simulated session "
                  "board moves its board at every scan)");
    cmd->add_flag("--response", args->response,
                  "first record the projector's response (a ramp of grey levels on the board "
                  "at the first pose), which `calibrate` fits into projector-response.yaml "
                  "for the board file's projector_response");
    cmd->add_option("--pose-timeout", args->pose_timeout_s,
                    "seconds a pose's scan may take before the command gives up")
        ->capture_default_str();
    cmd->add_flag("--check", args->check,
                  "after each pose from the third, check the session so far as session-check "
                  "does (the trueness so far, the next pose in words) and stop once it is "
                  "enough (--poses is then the most)");
    cmd->add_option("--target-um", args->target_um,
                    "--check's target: 1 sigma of a 150 mm length along depth (micrometres)")
        ->capture_default_str();
    return action;
}

} // namespace fpp::calib
