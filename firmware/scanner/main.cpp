// fpp-scanner: the scanner head's firmware. Waits for the button, scans,
// writes the point cloud into the scan store; --once (or --scans N) scans
// once (N times) and exits.
#include "fpp/drivers/device_error.hpp"
#include "fpp/error.hpp"
#include "fpp/scanner/board_config.hpp"
#include "fpp/scanner/hardware_board.hpp"
#include "fpp/scanner/log.hpp"
#include "fpp/scanner/scanner.hpp"
#include "fpp/scanner/sim_board.hpp"

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

namespace {

std::atomic<bool> g_stop{false};

extern "C" void on_stop_signal(int) { g_stop.store(true); }

void usage(std::FILE* out) {
    std::fputs("usage: fpp-scanner --board FILE [--once | --scans N] [--mode scan|capture]\n"
               "                   [--store DIR] [--table FILE]\n"
               "  --board FILE   board configuration (fpp-scanner-board/1, e.g. board/sim.yaml)\n"
               "  --once         scan once as if the button had been pressed, print the output\n"
               "                 folder and exit (0 only when the outputs are written)\n"
               "  --scans N      the same N times in a row, one output folder per line\n"
               "  --mode M       scan: point cloud (needs the board's table); capture: also the\n"
               "                 raw capture set (calibration sessions)\n"
               "  --store DIR    scan store directory (overrides the board's)\n"
               "  --table FILE   coefficient table (overrides the board's)\n",
               out);
}

} // namespace

int main(int argc, char** argv) {
    using namespace fpp::scanner;
    std::string board_path;
    std::string store;
    std::string table;
    bool once = false;
    int scans = 0; // --scans N; --once is --scans 1
    ScanMode mode = ScanMode::scan;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has_value = i + 1 < argc;
        if (a == "--board" && has_value) board_path = argv[++i];
        else if (a == "--store" && has_value) store = argv[++i];
        else if (a == "--table" && has_value) table = argv[++i];
        else if (a == "--once") once = true;
        else if (a == "--scans" && has_value) {
            const std::string n = argv[++i];
            char* end = nullptr;
            const long v = std::strtol(n.c_str(), &end, 10);
            if (n.empty() || *end != '\0' || v < 1 || v > 100000) {
                std::fprintf(stderr, "error: --scans must be 1..100000, not '%s'\n", n.c_str());
                return 2;
            }
            scans = static_cast<int>(v);
        }
        else if (a == "--mode" && has_value) {
            const std::string m = argv[++i];
            if (m == "scan") mode = ScanMode::scan;
            else if (m == "capture") mode = ScanMode::capture;
            else {
                std::fprintf(stderr, "error: --mode must be scan or capture, not '%s'\n", m.c_str());
                return 2;
            }
        } else if (a == "--help" || a == "-h") {
            usage(stdout);
            return 0;
        } else {
            std::fprintf(stderr, "error: unknown or incomplete argument '%s'\n", a.c_str());
            usage(stderr);
            return 2;
        }
    }
    if (board_path.empty()) {
        usage(stderr);
        return 2;
    }

    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGTERM, &action, nullptr);
    sigaction(SIGINT, &action, nullptr);

    const Logger log;
    try {
        BoardConfig board = read_board_config(board_path);
        if (!store.empty()) board.store.directory = store;
        if (!table.empty()) board.table = table;
        // Capture mode records calibration sessions, made before any table
        // exists: it neither needs nor loads one.
        if (mode == ScanMode::capture) board.table.reset();
        // A board file with a sim section is the virtual scanner; without one
        // the hardware. Devices that cannot be opened throw DeviceError.
        std::unique_ptr<SimBoard> sim;
        std::unique_ptr<HardwareBoard> hardware;
        if (board.sim) sim = std::make_unique<SimBoard>(board);
        else {
            hardware = std::make_unique<HardwareBoard>(board);
            // As a service the scanner waits for a camera that does not
            // answer yet (LED in error); --once and --scans fail at once.
            if (once || scans > 0) hardware->open_camera();
            else if (!hardware->wait_for_camera(log, g_stop)) {
                hardware->led().set(fpp::drivers::LedState::off);
                hardware->display().restore();
                log.info("stopped while waiting for the camera");
                return 0;
            }
        }
        Devices devices = sim ? sim->devices() : hardware->devices();
        // Lines and display are released by the destructors, on every path.
        try {
            Scanner scanner(board, devices, log);
            if (once && scans == 0) scans = 1;
            if (scans > 0) {
                for (int k = 0; k < scans; ++k) {
                    const ScanOutcome outcome = scanner.scan(mode, &g_stop);
                    std::printf("%s\n", outcome.folder.string().c_str());
                    std::fflush(stdout);
                }
                devices.display.restore();
                return 0;
            }
            scanner.run(mode, g_stop);
            devices.display.restore();
            log.info("stopped");
            return 0;
        } catch (const ScanAborted&) {
            devices.display.restore(); // logged by the scanner; LED already off
            return 1;
        } catch (...) {
            devices.led.set(fpp::drivers::LedState::error);
            devices.display.restore();
            throw;
        }
    } catch (const fpp::InputError& e) {
        log.error(e.what());
    } catch (const fpp::IoError& e) {
        log.error(e.what());
    } catch (const fpp::drivers::DeviceError& e) {
        log.error(e.what());
    } catch (const std::exception& e) {
        log.error(e.what());
    }
    return 1;
}
