// fpp-scanner: the scanner head's firmware. Waits for the button (and, with
// an HTTP listener, for requests: firmware/scanner/http-api.md), scans,
// writes the point cloud into the scan store; --once (or --scans N) scans
// once (N times) and exits.
#include "fpp/atomic_file.hpp"
#include "fpp/drivers/device_error.hpp"
#include "fpp/error.hpp"
#include "fpp/scanner/api_events.hpp"
#include "fpp/scanner/board_config.hpp"
#include "fpp/scanner/hardware_board.hpp"
#include "fpp/scanner/log.hpp"
#include "fpp/scanner/networked_scanner.hpp"
#include "fpp/scanner/scan_store.hpp"
#include "fpp/scanner/scanner.hpp"
#include "fpp/scanner/scanner_service.hpp"
#include "fpp/scanner/settings_file.hpp"
#if FPP_SCANNER_SIM
#include "fpp/scanner/sim_board.hpp"
#endif

#include <CLI/CLI.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

std::atomic<bool> g_stop{false};

extern "C" void on_stop_signal(int) {
    g_stop.store(true);
}

struct Options {
    std::string board;
    std::string store;
    std::string table;
    std::string settings;
    std::string http;
    std::string token_file;
    std::string web_root;
    bool once = false;
    int scans = 0; // --scans N; --once is --scans 1
    std::string mode = "scan";
};

// The command line over the board file.
void apply_options(const Options& o, fpp::scanner::BoardConfig& board) {
    using namespace fpp::scanner;
    if (!o.store.empty())
        board.store.directory = o.store;
    if (!o.table.empty())
        board.table = o.table;
    if (!o.settings.empty())
        board.settings_file = o.settings;
    if (!o.http.empty() || !o.token_file.empty()) {
        if (!board.http)
            board.http.emplace();
        if (!o.http.empty())
            board.http->listen = o.http;
        if (!o.token_file.empty())
            board.http->token_file = o.token_file;
        if (board.http->listen.empty() || board.http->token_file.empty())
            throw fpp::InputError("command line", "--http",
                                  "--http ADDRESS:PORT and --token-file FILE go together");
        try {
            (void)parse_listen_address(board.http->listen);
        } catch (const std::invalid_argument& e) {
            throw fpp::InputError("command line", "--http", e.what());
        }
    }
    if (!o.web_root.empty() && board.http)
        board.http->web_root = o.web_root;
}

// The settings at start: the board file's, and over them what a person set
// last through the API (the settings file), applied to the camera.
fpp::scanner::ScannerSettings settings_at_start(const fpp::scanner::BoardConfig& board,
                                                fpp::drivers::Camera& camera) {
    fpp::scanner::ScannerSettings settings{board.camera.settings.exposure_us};
    if (!board.settings_file)
        return settings;
    if (const auto s = fpp::scanner::read_settings_file(*board.settings_file)) {
        camera.set_exposure_us(s->exposure_us);
        settings = *s;
    }
    return settings;
}

// A power cut or SIGKILL in the middle of a scan or of a table or settings
// install leaves hidden temporaries (the outputs themselves are renamed into
// place whole, or not at all). Nothing writes yet: they go now.
void remove_interrupted_writes_at_start(const fpp::scanner::BoardConfig& board,
                                        const std::optional<std::filesystem::path>& table_path,
                                        const fpp::scanner::Logger& log) {
    std::vector<std::string> removed =
        fpp::scanner::remove_interrupted_scans(board.store.directory);
    for (const auto& file : {table_path, board.settings_file})
        if (file)
            for (const auto& name : fpp::remove_interrupted_writes(
                     file->parent_path().empty() ? "." : file->parent_path(),
                     file->filename().string()))
                removed.push_back(name);
    if (removed.empty())
        return;
    std::string names;
    for (const auto& name : removed)
        names += (names.empty() ? "" : ", ") + name;
    log.warning("removed " + std::to_string(removed.size()) +
                " temporary file(s) left by writes cut short (power cut or kill): " + names);
}

int run(const Options& o, const fpp::scanner::Logger& log) {
    using namespace fpp::scanner;
    BoardConfig board = read_board_config(o.board);
#if !FPP_SCANNER_SIM
    // The device binary (FPP_SCANNER_SIM OFF) has no virtual scanner: a sim
    // board is refused before anything is touched.
    if (board.sim)
        throw fpp::InputError(board.file, "sim",
                              "this fpp-scanner was built without the virtual scanner "
                              "(FPP_SCANNER_SIM=OFF), so it runs hardware boards only (a board "
                              "file without a sim section)");
#endif
    apply_options(o, board);
    const ScanMode mode = o.mode == "capture" ? ScanMode::capture : ScanMode::scan;
    const int scans = o.scans > 0 ? o.scans : (o.once ? 1 : 0);
    const bool serving = board.http && scans == 0;
    // The table's path, kept for uploads even when no table is there yet.
    const std::optional<std::filesystem::path> table_path = board.table;
    // Capture mode records calibration sessions, made before any table
    // exists: it neither needs nor loads one. A network scanner starts
    // without one too, and takes one over the network.
    if (mode == ScanMode::capture && !serving)
        board.table.reset();
    remove_interrupted_writes_at_start(board, table_path, log);
    if (serving && board.table && !std::filesystem::exists(*board.table)) {
        log.warning("no table at " + board.table->string() +
                    ": capture mode only until one is installed (PUT /api/v1/table)");
        board.table.reset();
    }
    // A board file with a sim section is the virtual scanner; without one
    // the hardware. Devices that cannot be opened throw DeviceError.
    std::unique_ptr<HardwareBoard> hardware;
    std::optional<Devices> opened;
    std::string session_board_yaml; // a simulated session board's own
#if FPP_SCANNER_SIM
    std::unique_ptr<SimBoard> sim;
    if (board.sim) {
        sim = std::make_unique<SimBoard>(board, log);
        sim->limit_records(SimBoard::kDaemonRecordLimit);
        opened.emplace(sim->devices());
        session_board_yaml = sim->session_board_yaml();
    } else
#endif
    {
        hardware = std::make_unique<HardwareBoard>(board);
        // As a service the scanner waits for a camera that does not answer
        // yet (LED in error); --once and --scans fail at once.
        if (scans > 0)
            hardware->open_camera(log);
        else if (!hardware->wait_for_camera(log, g_stop)) {
            hardware->led().set(fpp::drivers::LedState::off);
            hardware->display().restore();
            log.info("stopped while waiting for the camera");
            return 0;
        }
        opened.emplace(hardware->devices());
    }
    Devices devices = *opened;
    const ScannerSettings settings = settings_at_start(board, devices.camera);
    // Lines and display are released by the destructors, on every path.
    try {
        std::optional<Scanner> made;
        try {
            made.emplace(board, settings, devices, log);
        } catch (const fpp::InputError& e) {
            // A network scanner with a bad table still serves, so that a
            // good one can be installed.
            if (!serving || !board.table || e.file() != *board.table)
                throw;
            log.error(std::string(e.what()) + ": serving without a table until one is installed");
            board.table.reset();
            made.emplace(board, settings, devices, log);
        }
        Scanner& scanner = *made;
        if (scans > 0) {
            for (int k = 0; k < scans; ++k) {
                const ScanOutcome outcome = scanner.scan(mode, &g_stop);
                std::printf("%s\n", outcome.folder.string().c_str());
                std::fflush(stdout);
            }
        } else {
            const ServiceOptions options{table_path, board.settings_file, session_board_yaml,
                                         board.sim.has_value()};
            if (serving) {
                NetworkedScanner networked(board, scanner, devices, log, options);
                networked.run(mode, g_stop);
            } else {
                EventHub events; // nobody listens without the network
                ApiEvents rendered(events);
                ScannerService service(board, scanner, devices, rendered, log, options);
                service.run(mode, g_stop);
            }
            log.info("stopped");
        }
        devices.display.restore();
        return 0;
    } catch (const ScanAborted&) {
        devices.display.restore(); // logged by the scanner; LED already off
        return 1;
    } catch (...) {
        devices.led.set(fpp::drivers::LedState::error);
        devices.display.restore();
        throw;
    }
}

} // namespace

int main(int argc, char** argv) {
    Options o;
    CLI::App app{"fpp-scanner: the scanner head's firmware. Without --once or --scans it runs "
                 "until SIGTERM: a button press scans, and with --http (or the board's http "
                 "section) so does a request."};
    app.add_option("--board", o.board,
                   "board configuration (fpp-scanner-board/1, e.g. board/sim.yaml)")
        ->required();
    app.add_flag("--once", o.once,
                 "scan once as if the button had been pressed, print the output folder and exit "
                 "(0 only when the outputs are written)");
    app.add_option("--scans", o.scans, "the same N times in a row, one output folder per line")
        ->check(CLI::Range(1, 100000));
    app.add_option("--mode", o.mode,
                   "scan: point cloud (needs the board's table); capture: also the raw capture "
                   "set (calibration sessions)")
        ->check(CLI::IsMember({"scan", "capture"}));
    app.add_option("--store", o.store, "scan store directory (overrides the board's)");
    app.add_option("--table", o.table, "coefficient table (overrides the board's)");
    app.add_option("--settings", o.settings,
                   "settings file the API may change (overrides the board's)");
    app.add_option("--http", o.http,
                   "serve the HTTP API and page on ADDRESS:PORT (port 0: any free port, "
                   "logged); needs --token-file");
    app.add_option("--token-file", o.token_file, "the API's bearer token, first line of FILE");
    app.add_option("--web-root", o.web_root, "the page's files (default: installed, else source)");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    }

    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGTERM, &action, nullptr);
    sigaction(SIGINT, &action, nullptr);
    // A client that goes away mid-download must not end the scanner.
    std::signal(SIGPIPE, SIG_IGN);

    const fpp::scanner::Logger log;
    try {
        return run(o, log);
    } catch (const std::exception& e) {
        // InputError, IoError and DeviceError name the file, field or device.
        log.error(e.what());
    }
    return 1;
}
