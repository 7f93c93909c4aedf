#pragma once
// The scanner on the network: the HTTP API and page (Api on an HttpServer),
// its events, and the ScannerService that runs the scans, wired from the
// board's http section. Lives on the thread that owns the devices.
#include <atomic>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <fpp/scanner/board_config.hpp>
#include <fpp/scanner/log.hpp>
#include <fpp/scanner/scanner.hpp>
#include <fpp/scanner/scanner_service.hpp>

namespace fpp::scanner {

class NetworkedScanner {
public:
    // Reads the token, finds the page and starts listening (logged as
    // "http: listening on ADDRESS:PORT"). Throws InputError for a bad token
    // file, IoError when it cannot listen.
    NetworkedScanner(const BoardConfig& board, Scanner& scanner, Devices devices, const Logger& log,
                     ServiceOptions options);
    ~NetworkedScanner();
    NetworkedScanner(const NetworkedScanner&) = delete;
    NetworkedScanner& operator=(const NetworkedScanner&) = delete;

    // Button presses (scans in `button_mode`) and requests until `stop`.
    void run(ScanMode button_mode, const std::atomic<bool>& stop);

    int port() const;

private:
    struct Stack;
    std::unique_ptr<Stack> stack_;
};

// Where the page's files are: the board's (or --web-root), else installed
// beside the binary (BIN/../share/fpp-scanner/web), else the source folder
// the binary was built from.
std::filesystem::path find_web_root(const std::optional<std::filesystem::path>& configured);

} // namespace fpp::scanner
