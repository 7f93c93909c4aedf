#pragma once
// A small HTTP/1.1 server on libmicrohttpd: one thread per connection (a
// bounded number), a timeout per idle connection, request bodies limited and
// either kept in memory or spooled to a file. The HttpHandler decides, per
// request, what is allowed; this file knows nothing of the API.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <fpp/scanner/log.hpp>

struct MHD_Daemon;

namespace fpp::scanner {

struct HttpRequest {
    std::string method;        // "GET", "PUT", ...
    std::string path;          // percent-decoded, without the query
    std::string authorization; // the Authorization header, "" when absent
    std::string if_none_match; // the If-None-Match header, "" when absent
    std::string content_type;
    std::string body;                // when the body is kept in memory
    std::filesystem::path body_file; // when it was spooled to a file
    std::uint64_t body_bytes = 0;
};

// Pulls a response body of unknown length piece by piece (chunked transfer):
// read() fills up to `max` bytes and returns how many; 0 ends the body. An
// exception ends the connection without a proper end, so the client sees
// the transfer fail.
class HttpStream {
public:
    virtual ~HttpStream() = default;
    virtual std::size_t read(char* out, std::size_t max) = 0;
};

struct HttpResponse {
    int status = 200;
    std::string content_type = "application/json";
    std::vector<std::pair<std::string, std::string>> headers;
    std::string body;
    std::optional<std::filesystem::path> file; // sent from the file instead of body
    std::shared_ptr<HttpStream> stream;        // or streamed

    static HttpResponse json(int status, std::string body);
    static HttpResponse error(int status, const std::string& message); // {"error": message}
    static HttpResponse no_content();                                  // 204
};

// Where a request's body may go, decided once its headers are in.
struct BodyPolicy {
    std::uint64_t max_bytes = 0;                    // 0: no body allowed
    std::optional<std::filesystem::path> spool_dir; // a file there instead of memory
};

class HttpHandler {
public:
    virtual ~HttpHandler() = default;
    // Headers read, no body yet: a response to send at once (refused:
    // 401, 404, ...), or nullopt and the body's policy in `policy`.
    virtual std::optional<HttpResponse> begin(const HttpRequest& request, BodyPolicy& policy) = 0;
    // The whole request is in.
    virtual HttpResponse handle(HttpRequest& request) = 0;
};

struct HttpServerOptions {
    std::string host = "127.0.0.1"; // IPv4 or IPv6 literal
    int port = 0;                   // 0: any free port (see HttpServer::port)
    int max_connections = 64;
    std::chrono::seconds timeout{30};
    // Headers and buffers of one connection: a request line or header block
    // beyond it gets libmicrohttpd's own (HTML) answer; within it, longer
    // than the limits below, a JSON 414 or 431.
    std::size_t connection_memory = 64 * 1024;
    std::size_t max_target = 8 * 1024;   // bytes of the request target (414)
    std::size_t max_headers = 16 * 1024; // bytes of the header fields (431)
};

class HttpServer {
public:
    // Binds, listens and starts serving. Throws IoError naming the address
    // when it cannot (address in use, bad address).
    HttpServer(const HttpServerOptions& options, HttpHandler& handler, const Logger& log);
    ~HttpServer(); // stops: waits for the connections' threads
    HttpServer(const HttpServer&) = delete;
    HttpServer& operator=(const HttpServer&) = delete;

    int port() const { return port_; }
    std::string address() const; // "HOST:PORT"

    struct Context; // what libmicrohttpd's callbacks get (http_server.cpp)

private:
    struct DaemonStop {
        void operator()(MHD_Daemon* d) const;
    };
    HttpServerOptions options_;
    int port_ = 0;
    std::unique_ptr<Context> context_;               // outlives the daemon:
    std::unique_ptr<MHD_Daemon, DaemonStop> daemon_; // stopped first
};

} // namespace fpp::scanner
