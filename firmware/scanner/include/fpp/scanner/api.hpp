#pragma once
// The HTTP API of firmware/scanner/http-api.md and the page's static files,
// as an HttpHandler: the token check, the limits on bodies, ids and names
// checked before any path is made from them, and each route's answer. The
// scanner's work is the ScannerService's; the store is read here.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <fpp/scanner/event_hub.hpp>
#include <fpp/scanner/http_server.hpp>
#include <fpp/scanner/scanner_service.hpp>

namespace fpp::scanner {

struct ApiOptions {
    std::string token;                 // the bearer token (access_token.hpp)
    std::filesystem::path web_root;    // the page's files
    std::filesystem::path three_root;  // three.js (Debian's libjs-three)
    std::uint64_t max_table_bytes = 0; // uploads beyond are refused (413)
};

class Api final : public HttpHandler {
public:
    Api(ScannerService& service, EventHub& events, const Logger& log, ApiOptions options);

    std::optional<HttpResponse> begin(const HttpRequest& request, BodyPolicy& policy) override;
    HttpResponse handle(HttpRequest& request) override;

private:
    HttpResponse route(HttpRequest& request, const std::vector<std::string>& parts);
    HttpResponse scans(HttpRequest& request, const std::vector<std::string>& parts);
    HttpResponse sessions(HttpRequest& request, const std::vector<std::string>& parts);
    HttpResponse scan_file(const std::filesystem::path& folder, const std::string& file);
    HttpResponse events();
    HttpResponse preview();
    HttpResponse settings(HttpRequest& request);
    HttpResponse table(HttpRequest& request);
    HttpResponse static_file(const HttpRequest& request);

    ScannerService& service_;
    EventHub& events_;
    const Logger& log_;
    ApiOptions options_;
};

} // namespace fpp::scanner
