// The API's routes and their dispatch (fpp/scanner/api_routes.hpp); the
// handlers are in api.cpp.

#include "fpp/scanner/api_routes.hpp"

#include "fpp/scanner/api.hpp"

#include <algorithm>
#include <array>

namespace fpp::scanner {

namespace fs = std::filesystem;

namespace {

bool is_digits(std::string_view s, std::size_t min, std::size_t max) {
    return s.size() >= min && s.size() <= max &&
           std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

bool is_parameter(std::string_view segment) {
    return segment.size() > 2 && segment.front() == '{' && segment.back() == '}';
}

} // namespace

std::vector<std::string> split_path(const std::string& path) {
    std::vector<std::string> parts;
    std::size_t i = 0;
    while (i < path.size()) {
        const std::size_t j = path.find('/', i);
        const std::size_t end = j == std::string::npos ? path.size() : j;
        if (end > i)
            parts.push_back(path.substr(i, end - i));
        i = end + 1;
    }
    return parts;
}

bool route_matches(std::string_view pattern, const std::vector<std::string>& parts) {
    const std::vector<std::string> segments = split_path(std::string(pattern));
    if (segments.size() != parts.size())
        return false;
    for (std::size_t i = 0; i < parts.size(); ++i)
        if (!is_parameter(segments[i]) && segments[i] != parts[i])
            return false;
    return true;
}

bool is_scan_id(const std::string& s) {
    constexpr std::string_view prefix = "scan-";
    if (!s.starts_with(prefix) || s.size() < 24 || s[13] != '-' || s[20] != '-')
        return false;
    const std::string_view v = s;
    return is_digits(v.substr(5, 8), 8, 8) && is_digits(v.substr(14, 6), 6, 6) &&
           is_digits(v.substr(21, 3), 3, 3) &&
           (s.size() == 24 || (s[24] == '-' && is_digits(v.substr(25), 1, 6)));
}

bool is_plain_name(std::string_view s, std::size_t max) {
    const auto allowed = [](char c) {
        return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
               c == '.' || c == '_' || c == '-';
    };
    return !s.empty() && s.size() <= max && s[0] != '.' && std::all_of(s.begin(), s.end(), allowed);
}

bool is_session_name(const std::string& s) {
    return is_plain_name(s, 64);
}

HttpResponse method_not_allowed(const std::string& allowed) {
    HttpResponse r = HttpResponse::error(405, "method not allowed here (allowed: " + allowed + ")");
    r.headers.emplace_back("Allow", allowed);
    return r;
}

std::span<const ApiRoute> Api::routes() {
    // Each path's methods in the order its Allow header lists them.
    static const std::array kRoutes = {
        ApiRoute{"GET", "/api/v1/status", &Api::get_status},
        ApiRoute{"GET", "/api/v1/scans", &Api::scan_list},
        ApiRoute{"POST", "/api/v1/scans", &Api::start_scan},
        ApiRoute{"GET", "/api/v1/scans/{id}", &Api::get_scan_json},
        ApiRoute{"DELETE", "/api/v1/scans/{id}", &Api::delete_scan},
        ApiRoute{"GET", "/api/v1/scans/{id}/cloud.ply", &Api::get_scan_file},
        ApiRoute{"GET", "/api/v1/scans/{id}/capture.tar", &Api::get_scan_file},
        ApiRoute{"GET", "/api/v1/scans/{id}/texture.png", &Api::get_scan_file},
        ApiRoute{"GET", "/api/v1/events", &Api::get_events},
        ApiRoute{"GET", "/api/v1/preview.png", &Api::get_preview},
        ApiRoute{"GET", "/api/v1/settings", &Api::get_settings},
        ApiRoute{"PUT", "/api/v1/settings", &Api::put_settings},
        ApiRoute{"GET", "/api/v1/table", &Api::get_table},
        ApiRoute{"PUT", "/api/v1/table", &Api::put_table},
        ApiRoute{"GET", "/api/v1/sessions", &Api::session_list},
        ApiRoute{"POST", "/api/v1/sessions", &Api::create_session},
        ApiRoute{"GET", "/api/v1/sessions/{name}", &Api::get_session},
        ApiRoute{"DELETE", "/api/v1/sessions/{name}", &Api::delete_session},
        ApiRoute{"POST", "/api/v1/sessions/{name}/poses", &Api::start_pose},
        ApiRoute{"GET", "/api/v1/sessions/{name}/poses/{id}", &Api::get_scan_json},
        ApiRoute{"DELETE", "/api/v1/sessions/{name}/poses/{id}", &Api::delete_pose},
        ApiRoute{"GET", "/api/v1/sessions/{name}/poses/{id}/cloud.ply", &Api::get_scan_file},
        ApiRoute{"GET", "/api/v1/sessions/{name}/poses/{id}/capture.tar", &Api::get_scan_file},
        ApiRoute{"GET", "/api/v1/sessions/{name}/poses/{id}/texture.png", &Api::get_scan_file},
        ApiRoute{"POST", "/api/v1/sessions/{name}/response", &Api::record_response},
        ApiRoute{"GET", "/api/v1/sessions/{name}/session.tar", &Api::get_session_tar},
    };
    return kRoutes;
}

HttpResponse Api::route(HttpRequest& request, const std::vector<std::string>& parts) {
    // Every pattern matching a path is the same one: no two differ only where
    // one has a parameter and the other a literal.
    std::vector<const ApiRoute*> matched;
    for (const ApiRoute& r : routes())
        if (route_matches(r.pattern, parts))
            matched.push_back(&r);
    if (matched.empty())
        return HttpResponse::error(404, "no such path");

    // What the path names must exist (404), whatever the method.
    const std::vector<std::string> segments = split_path(std::string(matched.front()->pattern));
    RouteParams params;
    params.last_segment = parts.back();
    for (std::size_t i = 0; i < segments.size(); ++i) {
        if (segments[i] == "{name}") {
            params.name = parts[i];
            params.folder = service_.sessions_dir() / params.name;
            if (!is_session_name(params.name) || !fs::is_directory(params.folder))
                return HttpResponse::error(404, "no session '" + params.name + "'");
        } else if (segments[i] == "{id}") {
            params.id = parts[i];
            const bool pose = !params.name.empty();
            params.folder = (pose ? params.folder : service_.store()) / params.id;
            if (!is_scan_id(params.id) || !fs::is_directory(params.folder))
                return HttpResponse::error(404, pose ? "no pose '" + params.id + "' in session '" +
                                                           params.name + "'"
                                                     : "no scan '" + params.id + "'");
        }
    }

    std::string allowed;
    for (const ApiRoute* r : matched) {
        if (r->method == request.method)
            return (this->*(r->handler))(request, params);
        allowed += (allowed.empty() ? "" : ", ") + std::string(r->method);
    }
    return method_not_allowed(allowed);
}

} // namespace fpp::scanner
