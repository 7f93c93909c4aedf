#pragma once
// The HTTP API of firmware/scanner/http-api.md and the page's static files,
// as an HttpHandler: the token check, the limits on bodies, ids and names
// checked before any path is made from them, and each route's answer. The
// scanner's work is the ScannerService's; the store is read here.
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <fpp/scanner/api_routes.hpp>
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

    // The routes of http-api.md, one table (api_routes.cpp).
    static std::span<const ApiRoute> routes();

private:
    // Finds the route of a path under /api/v1: 404 when no pattern matches or
    // a scan, session or pose it names does not exist, 405 with Allow when
    // the path is known but the method is not.
    HttpResponse route(HttpRequest& request, const std::vector<std::string>& parts);

    // The handlers of the table.
    HttpResponse get_status(HttpRequest& request, const RouteParams& params);
    HttpResponse scan_list(HttpRequest& request, const RouteParams& params);
    HttpResponse start_scan(HttpRequest& request, const RouteParams& params);
    HttpResponse get_scan_json(HttpRequest& request, const RouteParams& params);
    HttpResponse delete_scan(HttpRequest& request, const RouteParams& params);
    HttpResponse get_scan_file(HttpRequest& request, const RouteParams& params);
    HttpResponse get_events(HttpRequest& request, const RouteParams& params);
    HttpResponse get_preview(HttpRequest& request, const RouteParams& params);
    HttpResponse get_settings(HttpRequest& request, const RouteParams& params);
    HttpResponse put_settings(HttpRequest& request, const RouteParams& params);
    HttpResponse get_table(HttpRequest& request, const RouteParams& params);
    HttpResponse put_table(HttpRequest& request, const RouteParams& params);
    HttpResponse session_list(HttpRequest& request, const RouteParams& params);
    HttpResponse create_session(HttpRequest& request, const RouteParams& params);
    HttpResponse get_session(HttpRequest& request, const RouteParams& params);
    HttpResponse delete_session(HttpRequest& request, const RouteParams& params);
    HttpResponse get_session_tar(HttpRequest& request, const RouteParams& params);
    HttpResponse record_response(HttpRequest& request, const RouteParams& params);
    HttpResponse start_pose(HttpRequest& request, const RouteParams& params);
    HttpResponse delete_pose(HttpRequest& request, const RouteParams& params);

    HttpResponse static_file(const HttpRequest& request);

    ScannerService& service_;
    EventHub& events_;
    const Logger& log_;
    ApiOptions options_;
};

} // namespace fpp::scanner
