#pragma once
// A client of fpp-scanner's HTTP API v1 (firmware/scanner/http-api.md) on
// libcurl: the bearer token on every request, JSON bodies, downloads that
// appear whole or not at all, and the server-sent event stream. Every
// failure throws ScannerError naming the method, the URL, the HTTP status
// and the scanner's {"error": ...} text.

#include "fpp/calib/server_sent_events.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace fpp::calib {

class ScannerError : public std::runtime_error {
public:
    ScannerError(const std::string& what, long http_status = 0)
        : std::runtime_error(what), http_status_(http_status) {}
    // 0 when no HTTP answer came (no connection, timeout, ...).
    long http_status() const { return http_status_; }

private:
    long http_status_;
};

// The API token: the first line of `token_file` (16 to 256 printable ASCII
// characters, no spaces, as the scanner requires). Throws InputError naming
// the file.
std::string read_scanner_token(const std::filesystem::path& token_file);

class ScannerEventStream;

class ScannerClient {
public:
    // `base_url` is http://HOST:PORT (https also works; a trailing / is
    // dropped). Throws InputError for another scheme or a bad token.
    ScannerClient(std::string base_url, std::string token);

    const std::string& base_url() const { return base_url_; }
    std::string url(std::string_view path) const { return base_url_ + std::string(path); }

    // A request whose answer must be a 2xx JSON body (null when empty).
    nlohmann::json get_json(std::string_view path) const;
    // A null `body` is sent as no body at all.
    nlohmann::json post_json(std::string_view path, const nlohmann::json& body) const;
    // `bytes` as the body (application/octet-stream).
    nlohmann::json put_bytes(std::string_view path, std::string_view bytes) const;

    // GETs `path` into the file `target`, atomically: a temporary file beside
    // it, fsynced and renamed; nothing is left at `target` on failure.
    // Returns the number of bytes.
    std::uint64_t download(std::string_view path, const std::filesystem::path& target) const;

    // Opens GET /api/v1/events.
    ScannerEventStream events() const;

private:
    std::string base_url_;
    std::string token_;
};

// An open GET /api/v1/events. The transfer runs only inside next(): the
// kernel's socket buffer (and the scanner's queue of 256 events) holds what
// comes in meanwhile, so one thread can make other requests in between.
class ScannerEventStream {
public:
    ~ScannerEventStream();
    ScannerEventStream(ScannerEventStream&&) noexcept;
    ScannerEventStream& operator=(ScannerEventStream&&) noexcept;

    // The next event, or nothing after `timeout`. Throws ScannerError when
    // the stream fails, ends, is answered with an error status, or sends
    // nothing at all (not even its keep-alive, every 10 s) for
    // `silence_limit`.
    std::optional<ServerEvent> next(std::chrono::milliseconds timeout);

    static constexpr std::chrono::seconds silence_limit{35};

private:
    friend class ScannerClient;
    struct Transfer;
    explicit ScannerEventStream(std::unique_ptr<Transfer> transfer);
    std::unique_ptr<Transfer> transfer_;
};

} // namespace fpp::calib
