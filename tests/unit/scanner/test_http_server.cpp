// The scanner's HTTP/1.1 server (fpp/scanner/http_server.hpp) on loopback,
// with a handler written here: what the handler answers goes out with the
// server's own headers; the path percent-decoded (an escaped NUL left as it
// came); refusals before the body; bodies limited, kept in memory or spooled
// to a file that is removed afterwards; targets and header blocks too long
// answered as JSON; files and streams; a handler's exception a 500 and a log
// line; and the addresses it cannot listen on, named.

#include "fpp/scanner/http_server.hpp"

#include "fpp/error.hpp"
#include "loopback_http.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

using namespace fpp;
using namespace fpp::scanner;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

struct Reply {
    int status = 0;
    std::map<std::string, std::string> headers; // names in lower case
    std::string body;                           // de-chunked
    std::string header(const std::string& name) const {
        const auto found = headers.find(name);
        return found == headers.end() ? "" : found->second;
    }
};

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    return s;
}

// The answer to `request`, sent as it is (raw_exchange: the requests below
// say Connection: close), its head parsed and its body de-chunked.
Reply exchange(int port, const std::string& request) {
    const std::string data = fpp::test::raw_exchange(port, request);
    Reply r;
    const std::size_t head_end = data.find("\r\n\r\n");
    if (data.rfind("HTTP/1.1 ", 0) != 0 || head_end == std::string::npos)
        return r;
    r.status = std::stoi(data.substr(9, 3));
    for (std::size_t line = data.find("\r\n") + 2; line < head_end;) {
        const std::size_t end = data.find("\r\n", line);
        const std::string field = data.substr(line, end - line);
        const std::size_t colon = field.find(':');
        r.headers[lower(field.substr(0, colon))] =
            field.substr(field.find_first_not_of(' ', colon + 1));
        line = end + 2;
    }
    std::string body = data.substr(head_end + 4);
    if (r.header("transfer-encoding") == "chunked") {
        std::string plain;
        for (std::size_t at_ = 0;;) {
            const std::size_t size_end = body.find("\r\n", at_);
            const std::size_t size = std::stoul(body.substr(at_, size_end - at_), nullptr, 16);
            if (size == 0)
                break;
            plain += body.substr(size_end + 2, size);
            at_ = size_end + 2 + size + 2;
        }
        body = plain;
    }
    r.body = body;
    return r;
}

std::string request(const std::string& method, const std::string& target,
                    const std::string& body = {}, const std::string& more_headers = {}) {
    return method + " " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" + more_headers +
           (body.empty() ? "" : "Content-Length: " + std::to_string(body.size()) + "\r\n") +
           "Connection: close\r\n\r\n" + body;
}

class Pieces final : public HttpStream {
public:
    std::size_t read(char* out, std::size_t max) override {
        if (next_ == 3)
            return 0;
        const std::string piece = "piece" + std::to_string(next_++) + ";";
        const std::size_t n = std::min(max, piece.size());
        std::memcpy(out, piece.data(), n);
        return n;
    }

private:
    int next_ = 0;
};

// Echoes what it got as JSON; a few paths do something else.
class EchoHandler final : public HttpHandler {
public:
    explicit EchoHandler(fs::path spool) : spool_(std::move(spool)) {}
    std::optional<HttpResponse> begin(const HttpRequest& request, BodyPolicy& policy) override {
        if (request.path == "/refuse")
            return HttpResponse::error(401, "no token");
        if (request.path == "/upload")
            policy.max_bytes = 16;
        if (request.path == "/spool") {
            policy.max_bytes = 1 << 20;
            policy.spool_dir = spool_;
        }
        return std::nullopt;
    }
    HttpResponse handle(HttpRequest& request) override {
        if (request.path == "/throw")
            throw std::runtime_error("the handler broke");
        if (request.path == "/file" || request.path == "/missing-file") {
            HttpResponse r;
            r.content_type = "text/plain";
            r.file = spool_ / (request.path == "/file" ? "served.txt" : "absent.txt");
            return r;
        }
        if (request.path == "/stream") {
            HttpResponse r;
            r.content_type = "text/plain";
            r.stream = std::make_shared<Pieces>();
            return r;
        }
        if (request.path == "/empty")
            return HttpResponse::no_content();
        std::string spooled;
        if (!request.body_file.empty()) {
            EXPECT_EQ(request.body_file.parent_path(), spool_);
            std::ifstream in(request.body_file, std::ios::binary);
            std::ostringstream text;
            text << in.rdbuf();
            spooled = text.str();
        }
        HttpResponse r = HttpResponse::json(200, json{{"method", request.method},
                                                      {"path", request.path},
                                                      {"authorization", request.authorization},
                                                      {"body", request.body},
                                                      {"bytes", request.body_bytes},
                                                      {"spooled", spooled}}
                                                     .dump());
        r.headers.emplace_back("ETag", "\"e1\"");
        return r;
    }

private:
    fs::path spool_;
};

struct Lines {
    std::mutex mutex;
    std::vector<std::pair<LogLevel, std::string>> lines;
    Logger logger() {
        return Logger([this](LogLevel level, const std::string& m) {
            std::lock_guard lock(mutex);
            lines.emplace_back(level, m);
        });
    }
};

struct Server {
    test::TempDir dir;
    EchoHandler handler{dir.path()};
    Lines log;
    Logger logger = log.logger();
    HttpServer server;
    explicit Server(HttpServerOptions options = {}) : server(options, handler, logger) {}
    Reply send(const std::string& text) { return exchange(server.port(), text); }
};

TEST(HttpServer, WhatTheHandlerAnswersGoesOutWithTheServersHeaders) {
    Server s;
    EXPECT_GT(s.server.port(), 0);
    EXPECT_EQ(s.server.address(), "127.0.0.1:" + std::to_string(s.server.port()));
    const Reply r = s.send(request("GET", "/hello", "", "Authorization: Bearer abc\r\n"));
    EXPECT_EQ(r.status, 200);
    EXPECT_EQ(r.header("content-type"), "application/json");
    EXPECT_EQ(r.header("x-content-type-options"), "nosniff");
    EXPECT_EQ(r.header("referrer-policy"), "no-referrer");
    EXPECT_EQ(r.header("etag"), "\"e1\"");
    EXPECT_EQ(json::parse(r.body), (json{{"method", "GET"},
                                         {"path", "/hello"},
                                         {"authorization", "Bearer abc"},
                                         {"body", ""},
                                         {"bytes", 0},
                                         {"spooled", ""}}));
    EXPECT_EQ(s.send(request("DELETE", "/empty")).status, 204);
}

TEST(HttpServer, ThePathIsPercentDecodedWithoutTheQueryAnEscapedNulLeftAsItCame) {
    Server s;
    EXPECT_EQ(json::parse(s.send(request("GET", "/a%20b%2Fc")).body)["path"], "/a b/c");
    EXPECT_EQ(json::parse(s.send(request("GET", "/scans?since=3")).body)["path"], "/scans");
    EXPECT_EQ(json::parse(s.send(request("GET", "/scans/x%00/cloud.ply")).body)["path"],
              "/scans/x%00/cloud.ply");
}

TEST(HttpServer, TheHandlerRefusesBeforeTheBody) {
    Server s;
    const Reply r = s.send(request("PUT", "/refuse", "a body nobody reads"));
    EXPECT_EQ(r.status, 401);
    EXPECT_EQ(r.body, R"({"error":"no token"})");
}

TEST(HttpServer, BodiesWithinTheLimitAreKeptInMemoryOthersRefused) {
    Server s;
    const Reply kept = s.send(request("POST", "/upload", "sixteen bytes ok"));
    EXPECT_EQ(kept.status, 200);
    EXPECT_EQ(json::parse(kept.body)["body"], "sixteen bytes ok");
    EXPECT_EQ(json::parse(kept.body)["bytes"], 16);
    const Reply over = s.send(request("POST", "/upload", "seventeen bytes !"));
    EXPECT_EQ(over.status, 413);
    EXPECT_EQ(json::parse(over.body)["error"], "the body is 17 bytes, at most 16 are taken here");
    const Reply none = s.send(request("POST", "/hello", "x"));
    EXPECT_EQ(none.status, 413);
    EXPECT_EQ(json::parse(none.body)["error"], "the body is 1 bytes, at most 0 are taken here");
    // Without a length (chunked), refused once it passes the limit.
    const Reply chunked =
        s.send("POST /upload HTTP/1.1\r\nHost: 127.0.0.1\r\nTransfer-Encoding: chunked\r\n"
               "Connection: close\r\n\r\n10\r\n0123456789abcdef\r\n4\r\nmore\r\n0\r\n\r\n");
    EXPECT_EQ(chunked.status, 413);
    EXPECT_EQ(json::parse(chunked.body)["error"],
              "the body passed 16 bytes, at most that many are taken here");
}

TEST(HttpServer, ASpooledBodyIsAFileRemovedAfterTheRequest) {
    Server s;
    const std::string body(5000, 'z');
    const Reply r = s.send(request("PUT", "/spool", body));
    EXPECT_EQ(r.status, 200);
    const json answer = json::parse(r.body);
    EXPECT_EQ(answer["body"], "");
    EXPECT_EQ(answer["bytes"], 5000);
    EXPECT_EQ(answer["spooled"], body);
    // The handler did not take the file: nothing is left in the spool folder.
    EXPECT_TRUE(test::entries_under(s.dir.path()).empty());
}

TEST(HttpServer, TargetsAndHeaderBlocksTooLongAreAnsweredAsJson) {
    HttpServerOptions options;
    options.max_target = 100;
    options.max_headers = 300;
    Server s(options);
    const Reply target = s.send(request("GET", "/" + std::string(100, 'a')));
    EXPECT_EQ(target.status, 414);
    EXPECT_EQ(json::parse(target.body)["error"],
              "the request target is 101 bytes, at most 100 are taken");
    EXPECT_EQ(s.send(request("GET", "/" + std::string(99, 'a'))).status, 200);
    const Reply headers =
        s.send(request("GET", "/hello", "", "X-Big: " + std::string(300, 'b') + "\r\n"));
    EXPECT_EQ(headers.status, 431);
    EXPECT_EQ(
        json::parse(headers.body)["error"].get<std::string>().rfind("the header fields are ", 0),
        0u);
}

TEST(HttpServer, FilesAndStreams) {
    Server s;
    std::ofstream(s.dir / "served.txt") << "the file's bytes\n";
    const Reply file = s.send(request("GET", "/file"));
    EXPECT_EQ(file.status, 200);
    EXPECT_EQ(file.header("content-type"), "text/plain");
    EXPECT_EQ(file.body, "the file's bytes\n");
    const Reply missing = s.send(request("GET", "/missing-file"));
    EXPECT_EQ(missing.status, 404);
    EXPECT_EQ(missing.body, R"({"error":"no such file"})");
    const Reply stream = s.send(request("GET", "/stream"));
    EXPECT_EQ(stream.status, 200);
    EXPECT_EQ(stream.header("transfer-encoding"), "chunked");
    EXPECT_EQ(stream.body, "piece0;piece1;piece2;");
}

TEST(HttpServer, AHandlersExceptionIsA500AndALogLine) {
    Server s;
    const Reply r = s.send(request("GET", "/throw"));
    EXPECT_EQ(r.status, 500);
    EXPECT_EQ(r.body, R"({"error":"the handler broke"})");
    std::lock_guard lock(s.log.mutex);
    ASSERT_EQ(s.log.lines.size(), 1u);
    EXPECT_EQ(s.log.lines[0].first, LogLevel::error);
    EXPECT_EQ(s.log.lines[0].second, "http: GET /throw: the handler broke");
}

TEST(HttpServer, AnAddressItCannotListenOnIsNamed) {
    test::TempDir dir;
    EchoHandler handler(dir.path());
    const Logger log{Logger::Sink{}};
    const auto what = [&](const HttpServerOptions& options) -> std::string {
        try {
            HttpServer server(options, handler, log);
        } catch (const IoError& e) {
            return e.what();
        }
        return "listening";
    };
    HttpServerOptions bad;
    bad.host = "scanner.local";
    EXPECT_EQ(what(bad), "scanner.local:0: not an IPv4 or IPv6 address");
    const HttpServer first({}, handler, log);
    HttpServerOptions taken;
    taken.port = first.port();
    EXPECT_EQ(what(taken).rfind("127.0.0.1:" + std::to_string(first.port()) + ": cannot listen", 0),
              0u)
        << what(taken);
}

TEST(HttpServer, ResponseHelpers) {
    const HttpResponse ok = HttpResponse::json(201, R"({"id":"a"})");
    EXPECT_EQ(ok.status, 201);
    EXPECT_EQ(ok.content_type, "application/json");
    EXPECT_EQ(ok.body, R"({"id":"a"})");
    EXPECT_EQ(HttpResponse::no_content().status, 204);
    EXPECT_EQ(HttpResponse::no_content().body, "");
    EXPECT_EQ(HttpResponse::error(400, "bad \"value\"").body, R"({"error":"bad \"value\""})");
    // Bytes that are not UTF-8 (quoted from a request) become U+FFFD.
    EXPECT_EQ(HttpResponse::error(400, "field \xff").body, "{\"error\":\"field \xef\xbf\xbd\"}");
}

} // namespace
