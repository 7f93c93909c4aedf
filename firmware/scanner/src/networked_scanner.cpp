#include "fpp/scanner/networked_scanner.hpp"

#include "fpp/error.hpp"
#include "fpp/scanner/access_token.hpp"
#include "fpp/scanner/api.hpp"
#include "fpp/scanner/api_events.hpp"
#include "fpp/scanner/event_hub.hpp"
#include "fpp/scanner/http_server.hpp"
#include "fpp/scanner/scanner_service.hpp"

namespace fpp::scanner {

namespace fs = std::filesystem;

namespace {
// Debian's libjs-three (the .deb depends on it).
const fs::path kThreeRoot = "/usr/share/javascript/three";
} // namespace

fs::path find_web_root(const std::optional<fs::path>& configured) {
    if (configured)
        return *configured;
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        const fs::path installed = exe.parent_path().parent_path() / "share/fpp-scanner/web";
        if (fs::exists(installed / "index.html"))
            return installed;
    }
    return FPP_SOURCE_WEB_ROOT;
}

// The service and what serves it, in construction order (destroyed in
// reverse: the server stops first).
struct NetworkedScanner::Stack {
    EventHub events;
    ApiEvents rendered{events};
    ScannerService service;
    Api api;
    HttpServer server; // last: stopped first
    Stack(const BoardConfig& board, Scanner& scanner, Devices devices, const Logger& log,
          ServiceOptions service_options, ApiOptions api_options, HttpServerOptions http)
        : service(board, scanner, devices, rendered, log, std::move(service_options)),
          api(service, events, log, std::move(api_options)), server(http, api, log) {}
};

NetworkedScanner::NetworkedScanner(const BoardConfig& board, Scanner& scanner, Devices devices,
                                   const Logger& log, ServiceOptions options) {
    const HttpConfig& h = *board.http;
    ApiOptions api;
    api.token = read_token_file(h.token_file);
    const fs::path web_root = find_web_root(h.web_root);
    if (!fs::exists(web_root / "index.html"))
        throw InputError(board.file, "http.web_root",
                         "no index.html in " + web_root.string() + " (the page's files)");
    api.web_root = web_root;
    api.three_root = kThreeRoot;
    // The largest table model is 14 floats a pixel; headers and tile CRCs
    // are far below the extra MiB.
    const Size camera = devices.camera.size();
    api.max_table_bytes = 64ull * static_cast<std::uint64_t>(camera.width) *
                              static_cast<std::uint64_t>(camera.height) +
                          (1ull << 20);
    const ListenAddress where = parse_listen_address(h.listen);
    HttpServerOptions http;
    http.host = where.host;
    http.port = where.port;
    http.max_connections = h.max_connections;
    http.timeout = h.timeout;
    stack_ = std::make_unique<Stack>(board, scanner, devices, log, std::move(options),
                                     std::move(api), http);
    log.info("http: listening on " + stack_->server.address() + " (page from " + web_root.string() +
             ")");
}

NetworkedScanner::~NetworkedScanner() {
    // Open event streams end first, so that the server's threads can finish.
    if (stack_)
        stack_->events.close();
}

void NetworkedScanner::run(ScanMode button_mode, const std::atomic<bool>& stop) {
    stack_->service.run(button_mode, stop);
    stack_->events.close();
}

int NetworkedScanner::port() const {
    return stack_->server.port();
}

} // namespace fpp::scanner
