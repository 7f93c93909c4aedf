#include "fpp/scanner/api.hpp"

#include "api_json.hpp"
#include "fpp/atomic_file.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/scanner/access_token.hpp"
#include "fpp/scanner/api_error.hpp"
#include "fpp/scanner/api_events.hpp"
#include "fpp/scanner/scan_store.hpp"
#include "fpp/yaml_fields.hpp"
#include "scan_metadata.hpp"
#include "tar_stream.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <string_view>

#include <sys/stat.h>

namespace fpp::scanner {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr std::uint64_t kMaxJsonBody = 64 * 1024;
constexpr auto kKeepAlive = std::chrono::seconds(10);

// A path segment of a static file.
bool is_plain_segment(const std::string& s) {
    return is_plain_name(s, 128);
}

std::string content_type_of(const fs::path& file) {
    const std::string ext = file.extension().string();
    if (ext == ".html")
        return "text/html; charset=utf-8";
    if (ext == ".js")
        return "text/javascript; charset=utf-8";
    if (ext == ".css")
        return "text/css; charset=utf-8";
    if (ext == ".png")
        return "image/png";
    if (ext == ".svg")
        return "image/svg+xml";
    if (ext == ".ico")
        return "image/x-icon";
    return "";
}

HttpResponse file_response(const fs::path& file, const std::string& type,
                           const std::string& download_name = {}) {
    if (!fs::is_regular_file(file))
        return HttpResponse::error(404, "no such file");
    HttpResponse r;
    r.file = file;
    r.content_type = type;
    if (!download_name.empty())
        r.headers.emplace_back("Content-Disposition",
                               "attachment; filename=\"" + download_name + "\"");
    return r;
}

json parse_body(const HttpRequest& request) {
    if (request.body.empty())
        return json::object();
    try {
        json j = json::parse(request.body);
        if (!j.is_object())
            throw ApiError(400, "the body must be a JSON object");
        return j;
    } catch (const json::exception& e) {
        // parse_error, and out_of_range for a number beyond a double (1e400).
        throw ApiError(400, std::string("the body is not JSON: ") + e.what());
    }
}

// A key that must be a string if present.
std::string string_field(const json& body, const char* key, const std::string& fallback) {
    if (!body.contains(key))
        return fallback;
    if (!body[key].is_string())
        throw ApiError(400, std::string(key) + ": must be a string");
    return body[key].get<std::string>();
}

void expect_keys(const json& body, std::initializer_list<const char*> allowed) {
    for (const auto& item : body.items()) {
        const std::string& key = item.key();
        if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; }))
            throw ApiError(400, key + ": unknown field");
    }
}

ScanMode mode_of(const std::string& text) {
    if (const auto mode = value_of(kScanModeNames, text))
        return *mode;
    throw ApiError(400, "mode: must be " + names_list(kScanModeNames, " or "));
}

// When a session was made: its board.yaml is written then, and only then.
json session_created_utc(const fs::path& session) {
    const auto t = file_written_utc(session / "board.yaml");
    return t ? json(*t) : json(nullptr);
}

// One entry of GET /scans (and a session's pose list).
json scan_summary(const fs::path& folder) {
    json entry = {{"id", folder.filename().string()}};
    try {
        const json meta = json::parse(yaml_fields::read_text_file(folder / "scan.json"));
        entry["mode"] = meta.value("mode", "");
        entry["started_utc"] = meta.value("started_utc", "");
        entry["points"] = meta.value("points", 0);
        entry["quality"] = meta.value("quality", json(nullptr));
    } catch (const std::exception&) {
        entry["mode"] = nullptr; // written by an older scanner, or damaged
    }
    entry["bytes"] = folder_bytes(folder);
    entry["cloud"] = fs::exists(folder / "cloud.ply");
    entry["capture"] = fs::exists(folder / "capture" / "capture.yaml");
    return entry;
}

// The frame under white light of a scan's capture set.
std::optional<fs::path> texture_of(const fs::path& folder) {
    const fs::path capture = folder / "capture";
    if (!fs::exists(capture / "capture.yaml"))
        return std::nullopt;
    try {
        const CaptureManifest m = read_manifest(capture / "capture.yaml");
        std::size_t frame = 0;
        for (const PatternBlock& block : m.sequence) {
            if (std::holds_alternative<WhiteBlock>(block))
                return frame < m.frames.size() ? std::optional(capture / m.frames[frame])
                                               : std::nullopt;
            frame += static_cast<std::size_t>(frame_count(block));
        }
    } catch (const std::exception&) {
    }
    return std::nullopt;
}

void remove_folder(const fs::path& folder) {
    std::error_code ec;
    fs::remove_all(folder, ec);
    if (ec)
        throw ApiError(500, "cannot remove " + folder.filename().string() + ": " + ec.message());
}

// Server-sent events of one client, from its subscription.
class EventStream final : public HttpStream {
public:
    explicit EventStream(std::shared_ptr<EventHub::Subscription> s) : subscription_(std::move(s)) {}
    std::size_t read(char* out, std::size_t max) override {
        while (offset_ == pending_.size()) {
            std::optional<std::string> next = subscription_->next(
                std::chrono::duration_cast<std::chrono::milliseconds>(kKeepAlive));
            if (!next)
                return 0; // the scanner stops
            pending_ = next->empty() ? std::string(": keep-alive\n\n") : std::move(*next);
            offset_ = 0;
        }
        const std::size_t n = std::min(max, pending_.size() - offset_);
        std::copy_n(pending_.data() + offset_, n, out);
        offset_ += n;
        return n;
    }

private:
    std::shared_ptr<EventHub::Subscription> subscription_;
    std::string pending_;
    std::size_t offset_ = 0;
};

} // namespace

Api::Api(ScannerService& service, EventHub& events, const Logger& log, ApiOptions options)
    : service_(service), events_(events), log_(log), options_(std::move(options)) {}

std::optional<HttpResponse> Api::begin(const HttpRequest& request, BodyPolicy& policy) {
    if (!request.path.starts_with("/api/"))
        return std::nullopt; // static files: no body
    if (!authorized(request.authorization, options_.token)) {
        HttpResponse r =
            HttpResponse::error(401, "a valid token is needed: Authorization: Bearer TOKEN");
        r.headers.emplace_back("WWW-Authenticate", "Bearer");
        return r;
    }
    if (request.method == "PUT" && request.path == "/api/v1/table") {
        const auto target = service_.table_path();
        if (!target)
            return HttpResponse::error(409, "the board names no table path (board key table, or "
                                            "--table)");
        std::error_code ec;
        fs::create_directories(target->parent_path(), ec);
        policy.max_bytes = options_.max_table_bytes;
        policy.spool_dir = target->parent_path(); // the same file system: installed by rename
    } else if (request.method == "POST" || request.method == "PUT") {
        policy.max_bytes = kMaxJsonBody;
    }
    return std::nullopt;
}

HttpResponse Api::handle(HttpRequest& request) {
    try {
        if (!request.path.starts_with("/api/")) {
            // The page's files are only read (libmicrohttpd answers HEAD
            // from the GET response).
            if (request.method != "GET" && request.method != "HEAD")
                return method_not_allowed("GET, HEAD");
            return static_file(request);
        }
        const auto parts = split_path(request.path);
        if (parts.size() < 2 || parts[1] != "v1")
            return HttpResponse::error(404, "no such path (the API is /api/v1)");
        HttpResponse r = route(request, parts);
        r.headers.emplace_back("Cache-Control", "no-store");
        return r;
    } catch (const ApiError& e) {
        return HttpResponse::error(e.status(), e.what());
    } catch (const InputError& e) {
        return HttpResponse::error(400, e.what());
    } catch (const IoError& e) {
        log_.error(std::string("http: ") + request.method + " " + request.path + ": " + e.what());
        return HttpResponse::error(500, e.what());
    }
}

HttpResponse Api::get_status(HttpRequest&, const RouteParams&) {
    return HttpResponse::json(200, api_json::status(service_.status()).dump());
}

HttpResponse Api::scan_list(HttpRequest&, const RouteParams&) {
    auto folders = list_scans(service_.store());
    std::reverse(folders.begin(), folders.end()); // newest first
    json list = json::array();
    for (const auto& f : folders) {
        json entry = scan_summary(f);
        std::error_code ec;
        if (fs::is_directory(f, ec)) // not deleted or pruned meanwhile
            list.push_back(std::move(entry));
    }
    return HttpResponse::json(200, json{{"scans", list}}.dump());
}

HttpResponse Api::start_scan(HttpRequest& request, const RouteParams&) {
    const json body = parse_body(request);
    expect_keys(body, {"mode"});
    const ScanMode mode = mode_of(string_field(body, "mode", "scan"));
    const std::string id = service_.start_scan(mode);
    HttpResponse r = HttpResponse::json(
        202, json{{"id", id}, {"mode", mode == ScanMode::scan ? "scan" : "capture"}}.dump());
    r.headers.emplace_back("Location", "/api/v1/scans/" + id);
    return r;
}

// A scan's or a pose's scan.json.
HttpResponse Api::get_scan_json(HttpRequest&, const RouteParams& params) {
    return file_response(params.folder / "scan.json", "application/json");
}

HttpResponse Api::delete_scan(HttpRequest&, const RouteParams& params) {
    remove_folder(params.folder);
    log_.info("http: scan " + params.id + " deleted");
    events_.publish("deleted", json{{"id", params.id}, {"session", nullptr}}.dump());
    return HttpResponse::no_content();
}

// cloud.ply, capture.tar or texture.png of a scan or a pose.
HttpResponse Api::get_scan_file(HttpRequest&, const RouteParams& params) {
    const fs::path& folder = params.folder;
    const std::string& file = params.last_segment;
    const std::string id = folder.filename().string();
    if (file == "cloud.ply")
        return file_response(folder / "cloud.ply", "application/octet-stream", id + "-cloud.ply");
    if (file == "texture.png") {
        const auto texture = texture_of(folder);
        return texture ? file_response(*texture, "image/png")
                       : HttpResponse::error(404, "the scan has no frame under white light");
    }
    if (file == "capture.tar") {
        if (!fs::exists(folder / "capture" / "capture.yaml"))
            return HttpResponse::error(404, "the scan has no capture set (scan mode)");
        HttpResponse r;
        r.content_type = "application/x-tar";
        r.stream = std::make_shared<TarStream>(tar_entries_of(folder / "capture", "capture/"));
        r.headers.emplace_back("Content-Disposition",
                               "attachment; filename=\"" + id + "-capture.tar\"");
        return r;
    }
    return HttpResponse::error(404, "no such file");
}

HttpResponse Api::session_list(HttpRequest&, const RouteParams&) {
    json list = json::array();
    std::error_code ec;
    std::vector<fs::path> folders;
    for (const auto& e : fs::directory_iterator(service_.sessions_dir(), ec))
        if (e.is_directory() && is_session_name(e.path().filename().string()))
            folders.push_back(e.path());
    std::sort(folders.begin(), folders.end());
    for (const auto& f : folders)
        list.push_back({{"name", f.filename().string()},
                        {"poses", list_scans(f).size()},
                        {"created_utc", session_created_utc(f)}});
    return HttpResponse::json(200, json{{"sessions", list}}.dump());
}

HttpResponse Api::create_session(HttpRequest& request, const RouteParams&) {
    const json body = parse_body(request);
    expect_keys(body, {"name", "board_yaml"});
    const std::string name = string_field(body, "name", "");
    if (!is_session_name(name))
        throw ApiError(400, "name: 1 to 64 of A-Z a-z 0-9 . _ -, not starting with .");
    std::string board = string_field(body, "board_yaml", service_.session_board_yaml());
    if (board.empty())
        throw ApiError(400, "board_yaml: needed (the calibration board, format " +
                                std::string(kBoardFormat) + ")");
    try {
        (void)parse_board(board, "board_yaml");
    } catch (const InputError& e) {
        throw ApiError(400, e.what());
    }
    const fs::path root = service_.sessions_dir();
    const fs::path folder = root / name;
    if (fs::exists(folder))
        throw ApiError(409, "session '" + name + "' exists");
    fs::create_directories(root);
    write_folder_atomically(
        folder, [&](const fs::path& temp) { write_file_synced(temp / "board.yaml", board); });
    log_.info("http: session " + name + " created");
    return HttpResponse::json(201, json{{"name", name}, {"poses", 0}}.dump());
}

HttpResponse Api::get_session(HttpRequest&, const RouteParams& params) {
    json poses = json::array();
    for (const auto& f : list_scans(params.folder))
        poses.push_back(scan_summary(f));
    std::string board;
    try {
        board = yaml_fields::read_text_file(params.folder / "board.yaml");
    } catch (const std::exception&) {
    }
    return HttpResponse::json(
        200, json{{"name", params.name}, {"board_yaml", board}, {"poses", poses}}.dump());
}

HttpResponse Api::delete_session(HttpRequest&, const RouteParams& params) {
    remove_folder(params.folder);
    log_.info("http: session " + params.name + " deleted");
    events_.publish("deleted", json{{"id", nullptr}, {"session", params.name}}.dump());
    return HttpResponse::no_content();
}

HttpResponse Api::get_session_tar(HttpRequest&, const RouteParams& params) {
    HttpResponse r;
    r.content_type = "application/x-tar";
    r.stream = std::make_shared<TarStream>(tar_entries_of(params.folder, params.name + "/"));
    r.headers.emplace_back("Content-Disposition",
                           "attachment; filename=\"" + params.name + ".tar\"");
    return r;
}

HttpResponse Api::record_response(HttpRequest&, const RouteParams& params) {
    return HttpResponse::json(201,
                              api_json::response(service_.record_response(params.name)).dump());
}

HttpResponse Api::start_pose(HttpRequest&, const RouteParams& params) {
    const std::string id = service_.start_scan(ScanMode::capture, params.name);
    HttpResponse r = HttpResponse::json(202, json{{"id", id}, {"session", params.name}}.dump());
    r.headers.emplace_back("Location", "/api/v1/sessions/" + params.name + "/poses/" + id);
    return r;
}

HttpResponse Api::delete_pose(HttpRequest&, const RouteParams& params) {
    remove_folder(params.folder);
    events_.publish("deleted", json{{"id", params.id}, {"session", params.name}}.dump());
    return HttpResponse::no_content();
}

HttpResponse Api::get_events(HttpRequest&, const RouteParams&) {
    HttpResponse r;
    r.content_type = "text/event-stream";
    r.headers.emplace_back("Cache-Control", "no-store");
    r.stream =
        std::make_shared<EventStream>(events_.subscribe(ApiEvents::state_event(service_.state())));
    return r;
}

HttpResponse Api::get_preview(HttpRequest&, const RouteParams&) {
    const Preview p = service_.preview();
    HttpResponse r;
    r.content_type = "image/png";
    r.body = p.png;
    r.headers.emplace_back("X-Preview-Saturated", std::to_string(p.saturated));
    r.headers.emplace_back("X-Preview-Mean", std::to_string(p.mean));
    return r;
}

HttpResponse Api::get_settings(HttpRequest&, const RouteParams&) {
    return HttpResponse::json(200, json{{"exposure_us", service_.exposure_us()}}.dump());
}

HttpResponse Api::put_settings(HttpRequest& request, const RouteParams& params) {
    const json body = parse_body(request);
    expect_keys(body, {"exposure_us"});
    if (!body.contains("exposure_us") || !body["exposure_us"].is_number())
        throw ApiError(400, "exposure_us: a number is needed");
    service_.set_exposure_us(body["exposure_us"].get<double>());
    return get_settings(request, params);
}

HttpResponse Api::get_table(HttpRequest&, const RouteParams&) {
    const std::optional<TableDescription> t = service_.table();
    if (!t)
        return HttpResponse::error(404, "no table is installed");
    return file_response(t->path, "application/octet-stream", "table.fpt");
}

HttpResponse Api::put_table(HttpRequest& request, const RouteParams&) {
    if (request.body_file.empty() || request.body_bytes == 0)
        throw ApiError(400, "the body must be the .fpt file");
    const TableDescription t = service_.install_table(request.body_file);
    request.body_file.clear(); // renamed into place
    log_.info(std::string("http: table installed (") + to_string(t.info.model) + ", hash " +
              hex64(t.file_hash) + ")");
    return HttpResponse::json(200, api_json::table(t).dump());
}

// Page files are revalidated on every load, three.js (from its Debian
// package, changed only by an upgrade) is kept a week; both carry an ETag
// from the file's size and modification time, and a matching If-None-Match
// gets 304 without the body.
HttpResponse Api::static_file(const HttpRequest& request) {
    const std::string& path = request.path;
    const auto parts = split_path(path == "/" ? "/index.html" : path);
    if (parts.empty() || !std::all_of(parts.begin(), parts.end(), is_plain_segment))
        return HttpResponse::error(404, "no such file");
    fs::path file;
    const bool three = parts[0] == "three" && parts.size() > 1;
    if (three) {
        file = options_.three_root;
        for (std::size_t i = 1; i < parts.size(); ++i)
            file /= parts[i];
    } else if (parts.size() == 1) {
        file = options_.web_root / parts[0];
    } else {
        return HttpResponse::error(404, "no such file");
    }
    const std::string type = content_type_of(file);
    if (type.empty())
        return HttpResponse::error(404, "no such file");
    struct stat st {};
    if (::stat(file.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
        return HttpResponse::error(404, "no such file");
    char etag[64];
    std::snprintf(etag, sizeof etag, "\"%llx-%llx\"", static_cast<unsigned long long>(st.st_size),
                  static_cast<unsigned long long>(st.st_mtim.tv_sec) * 1000000000ull +
                      static_cast<unsigned long long>(st.st_mtim.tv_nsec));
    const bool unchanged =
        request.if_none_match == "*" || request.if_none_match.find(etag) != std::string::npos;
    HttpResponse r = unchanged ? HttpResponse{} : file_response(file, type);
    if (unchanged) {
        r.status = 304;
        r.content_type = type;
    }
    r.headers.emplace_back("ETag", etag);
    r.headers.emplace_back("Cache-Control", three ? "public, max-age=604800" : "no-cache");
    r.headers.emplace_back("Content-Security-Policy",
                           "default-src 'self'; img-src 'self' blob: data:; "
                           "connect-src 'self'; style-src 'self'; frame-ancestors 'none'");
    return r;
}

} // namespace fpp::scanner
