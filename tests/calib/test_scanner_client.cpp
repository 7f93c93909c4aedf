// The host tool's client of fpp-scanner's HTTP API
// (fpp/calib/scanner_client.hpp), against the scanner's own HTTP server on
// loopback with a handler written here: the token file, the address and
// token refused, the bearer token and the Accept header on every request,
// JSON in and out, bytes up, a download whole or not at all, each failure
// named by method, URL, status and the scanner's error text, and the event
// stream to its end. (Against the real scanner: CliScannerNetwork.)

#include "fpp/calib/scanner_client.hpp"

#include "fpp/error.hpp"
#include "fpp/scanner/http_server.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <netinet/in.h>
#include <sys/socket.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

using fpp::InputError;
using fpp::calib::read_scanner_token;
using fpp::calib::ScannerClient;
using fpp::calib::ScannerError;
using fpp::scanner::BodyPolicy;
using fpp::scanner::HttpRequest;
using fpp::scanner::HttpResponse;
using nlohmann::json;
namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

const std::string kToken = "0123456789abcdef0123";

class Events final : public fpp::scanner::HttpStream {
public:
    std::size_t read(char* out, std::size_t max) override {
        if (sent_)
            return 0; // the stream ends
        sent_ = true;
        const std::string text = "event: state\ndata: {\"state\":\"idle\"}\n\n: keep-alive\n\n"
                                 "event: decoded\ndata: {\"id\":\"a\"}\n\n";
        const std::size_t n = std::min(max, text.size());
        std::memcpy(out, text.data(), n);
        return n;
    }

private:
    bool sent_ = false;
};

// A scanner's API in miniature: checks the token, answers by path.
class Scanner final : public fpp::scanner::HttpHandler {
public:
    std::optional<HttpResponse> begin(const HttpRequest& request, BodyPolicy& policy) override {
        if (request.authorization != "Bearer " + kToken)
            return HttpResponse::error(401, "missing or wrong token");
        policy.max_bytes = 1 << 16;
        return std::nullopt;
    }
    HttpResponse handle(HttpRequest& request) override {
        const std::string& p = request.path;
        if (p == "/api/v1/echo")
            return HttpResponse::json(200, json{{"method", request.method},
                                                {"content_type", request.content_type},
                                                {"body", request.body}}
                                               .dump());
        if (p == "/api/v1/nothing")
            return HttpResponse::no_content();
        if (p == "/api/v1/busy")
            return HttpResponse::error(409, "a scan is running");
        if (p == "/api/v1/plain")
            return plain(500, "out of memory\n");
        if (p == "/api/v1/silent")
            return plain(503, "");
        if (p == "/api/v1/not-json")
            return plain(200, "<html>a proxy's page</html>");
        if (p == "/api/v1/cloud.ply")
            return plain(200, std::string(100000, 'p'));
        if (p == "/api/v1/events") {
            HttpResponse r;
            r.content_type = "text/event-stream";
            r.stream = std::make_shared<Events>();
            return r;
        }
        return HttpResponse::error(404, "no such resource: " + p);
    }

private:
    static HttpResponse plain(int status, std::string body) {
        HttpResponse r = HttpResponse::json(status, std::move(body));
        r.content_type = "text/plain";
        return r;
    }
};

struct Loopback {
    Scanner handler;
    fpp::scanner::Logger log{fpp::scanner::Logger::Sink{}};
    fpp::scanner::HttpServer server{{}, handler, log};
    std::string base = "http://127.0.0.1:" + std::to_string(server.port());
    ScannerClient client{base + "/", kToken};
};

// The ScannerError `f` throws, as "status | message".
template <class F> std::string scanner_error(F&& f) {
    try {
        f();
    } catch (const ScannerError& e) {
        return std::to_string(e.http_status()) + " | " + e.what();
    }
    return "no ScannerError";
}

std::string text_of(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

TEST(ScannerClient, TheTokenFilesFirstLine) {
    fpp::test::TempDir dir;
    std::ofstream(dir / "token") << kToken << "\r\nignored\n";
    EXPECT_EQ(read_scanner_token(dir / "token"), kToken);
    std::ofstream(dir / "short") << "too short\n";
    try {
        read_scanner_token(dir / "short");
        FAIL() << "a short token taken";
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), dir / "short");
        EXPECT_EQ(e.field(), "token");
        EXPECT_EQ(std::string(e.what()), (dir / "short").string() +
                                             ": token: expected 16 to 256 printable ASCII "
                                             "characters without spaces, got 9 characters");
    }
    try {
        read_scanner_token(dir / "absent");
        FAIL() << "read a file that is not there";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()),
                  (dir / "absent").string() + ": cannot read the token file");
    }
}

TEST(ScannerClient, TheAddressAndTokenAreChecked) {
    const ScannerClient client("http://scanner.local:8080///", kToken);
    EXPECT_EQ(client.base_url(), "http://scanner.local:8080");
    EXPECT_EQ(client.url("/api/v1/status"), "http://scanner.local:8080/api/v1/status");
    EXPECT_EQ(ScannerClient("https://10.0.0.7", kToken).base_url(), "https://10.0.0.7");
    const auto refusal = [](const std::string& address) -> std::string {
        try {
            ScannerClient c(address, kToken);
        } catch (const std::invalid_argument& e) {
            return e.what();
        }
        return "took " + address;
    };
    for (const std::string bad : {"ftp://scanner.local", "scanner.local:8080", ""})
        EXPECT_EQ(refusal(bad), "scanner address \"" + bad + "\": expected http://HOST:PORT");
    // No host: quoted as it reads once the trailing slashes are dropped.
    EXPECT_EQ(refusal("http://"), "scanner address \"http:\": expected http://HOST:PORT");
    try {
        ScannerClient c("http://scanner.local", "with a space in it");
        FAIL() << "took a token with spaces";
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), "the scanner's API token");
        EXPECT_EQ(e.field(), "token");
    }
}

TEST(ScannerClient, JsonAndBytesWithTheToken) {
    Loopback s;
    EXPECT_EQ(s.client.base_url(), s.base);
    const json got = s.client.get_json("/api/v1/echo");
    EXPECT_EQ(got, (json{{"method", "GET"}, {"content_type", ""}, {"body", ""}}));
    const json posted = s.client.post_json("/api/v1/echo", json{{"mode", "scan"}});
    EXPECT_EQ(posted, (json{{"method", "POST"},
                            {"content_type", "application/json"},
                            {"body", R"({"mode":"scan"})"}}));
    EXPECT_EQ(s.client.post_json("/api/v1/echo", nullptr)["body"], "");
    const json put = s.client.put_bytes("/api/v1/echo", std::string("\x00\x01table", 7));
    EXPECT_EQ(put["method"], "PUT");
    EXPECT_EQ(put["content_type"], "application/octet-stream");
    EXPECT_EQ(put["body"], std::string("\x00\x01table", 7));
    EXPECT_TRUE(s.client.post_json("/api/v1/nothing", nullptr).is_null()); // 204
}

TEST(ScannerClient, FailuresNameMethodUrlStatusAndTheScannersText) {
    Loopback s;
    EXPECT_EQ(scanner_error([&] { s.client.post_json("/api/v1/busy", nullptr); }),
              "409 | POST " + s.base + "/api/v1/busy: HTTP 409 Conflict: a scan is running");
    EXPECT_EQ(scanner_error([&] { s.client.get_json("/api/v1/plain"); }),
              "500 | GET " + s.base +
                  "/api/v1/plain: HTTP 500 Internal Server Error: out of memory");
    EXPECT_EQ(scanner_error([&] { s.client.get_json("/api/v1/silent"); }),
              "503 | GET " + s.base +
                  "/api/v1/silent: HTTP 503 Service Unavailable (no error text)");
    EXPECT_EQ(scanner_error([&] { s.client.get_json("/api/v1/none"); }),
              "404 | GET " + s.base +
                  "/api/v1/none: HTTP 404 Not Found: no such resource: /api/v1/none");
    const ScannerClient wrong(s.base, "not-the-scanners-token");
    EXPECT_EQ(scanner_error([&] { wrong.get_json("/api/v1/echo"); }),
              "401 | GET " + s.base +
                  "/api/v1/echo: HTTP 401 Unauthorized: missing or wrong token (the token is "
                  "not the scanner's)");
    const std::string not_json = scanner_error([&] { s.client.get_json("/api/v1/not-json"); });
    EXPECT_EQ(not_json.rfind("0 | GET " + s.base + "/api/v1/not-json: the answer is not JSON (", 0),
              0u)
        << not_json;
}

TEST(ScannerClient, NoScannerThereSaysSo) {
    // A port that was just free: nothing listens on it.
    int port = 0;
    {
        fpp::scanner::Logger quiet{fpp::scanner::Logger::Sink{}};
        Scanner handler;
        const fpp::scanner::HttpServer server({}, handler, quiet);
        port = server.port();
    }
    const std::string base = "http://127.0.0.1:" + std::to_string(port);
    const std::string what =
        scanner_error([&] { ScannerClient(base, kToken).get_json("/api/v1/status"); });
    EXPECT_EQ(what.rfind("0 | GET " + base + "/api/v1/status: ", 0), 0u) << what;
    EXPECT_NE(what.find("(is fpp-scanner running there with its HTTP API on?)"), std::string::npos)
        << what;
}

TEST(ScannerClient, ADownloadAppearsWholeOrNotAtAll) {
    Loopback s;
    fpp::test::TempDir dir;
    EXPECT_EQ(s.client.download("/api/v1/cloud.ply", dir / "cloud.ply"), 100000u);
    EXPECT_EQ(text_of(dir / "cloud.ply"), std::string(100000, 'p'));
    EXPECT_EQ(scanner_error([&] { s.client.download("/api/v1/gone.ply", dir / "gone.ply"); }),
              "404 | GET " + s.base +
                  "/api/v1/gone.ply: HTTP 404 Not Found: no such resource: /api/v1/gone.ply");
    // Nothing at the target, nothing beside it.
    EXPECT_EQ(fpp::test::entries_under(dir.path()), std::vector<fs::path>{dir / "cloud.ply"});
}

TEST(ScannerClient, TheEventStreamToItsEnd) {
    Loopback s;
    auto events = s.client.events();
    const auto first = events.next(10s);
    ASSERT_TRUE(first.has_value());
    EXPECT_EQ(first->name, "state");
    EXPECT_EQ(first->data, R"({"state":"idle"})");
    const auto second = events.next(10s); // the keep-alive comment is no event
    ASSERT_TRUE(second.has_value());
    EXPECT_EQ(second->name, "decoded");
    EXPECT_EQ(second->data, R"({"id":"a"})");
    EXPECT_EQ(scanner_error([&] { events.next(10s); }),
              "0 | GET " + s.base + "/api/v1/events: the scanner closed the event stream");
}

} // namespace
