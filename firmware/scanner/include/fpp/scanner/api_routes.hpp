#pragma once
// The HTTP API's routes (firmware/scanner/http-api.md) as one table of
// method, path pattern and handler (Api::routes(), api_routes.cpp). Api
// answers 404 when no pattern matches the path and 405, with Allow listing
// the path's methods, when one does but not for this method; a test reads
// the endpoint list of http-api.md and compares it with the table.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace fpp::scanner {

class Api;
struct HttpRequest;
struct HttpResponse;

// What a matched path names, checked to exist before the handler runs.
struct RouteParams {
    std::string name;             // {name}: a session
    std::string id;               // {id}: a scan, or a pose of session {name}
    std::filesystem::path folder; // the scan's or pose's folder, else the session's
    std::string last_segment;     // the path's last segment ("cloud.ply")
};

struct ApiRoute {
    std::string_view method;  // GET, POST, PUT or DELETE
    std::string_view pattern; // "/api/v1/scans/{id}/cloud.ply": literals, {name} and {id}
    HttpResponse (Api::*handler)(HttpRequest&, const RouteParams&);
};

// A path's segments, empty ones dropped: "/api/v1//scans/" -> api, v1, scans.
std::vector<std::string> split_path(const std::string& path);

// Whether `pattern` matches the path `parts` (each {...} any one segment).
bool route_matches(std::string_view pattern, const std::vector<std::string>& parts);

// scan-YYYYMMDD-HHMMSS-mmm[-N] (scan_store.cpp's names).
bool is_scan_id(const std::string& s);
// 1 to 64 of A-Z a-z 0-9 . _ -, not starting with '.'.
bool is_session_name(const std::string& s);
// 1 to `max` of A-Z a-z 0-9 . _ -, not starting with '.' (so never "." or
// "..", nor a hidden file).
bool is_plain_name(std::string_view s, std::size_t max);

// 405 with Allow: `allowed` ("GET, PUT").
HttpResponse method_not_allowed(const std::string& allowed);

} // namespace fpp::scanner
