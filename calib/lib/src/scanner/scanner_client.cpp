#include "fpp/calib/scanner_client.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"

#include <curl/curl.h>

#include <algorithm>
#include <deque>
#include <exception>
#include <fstream>
#include <functional>
#include <vector>

namespace fpp::calib {

namespace {

struct EasyDeleter {
    void operator()(CURL* easy) const noexcept { curl_easy_cleanup(easy); }
};
struct MultiDeleter {
    void operator()(CURLM* multi) const noexcept { curl_multi_cleanup(multi); }
};
struct ListDeleter {
    void operator()(curl_slist* list) const noexcept { curl_slist_free_all(list); }
};
using CurlEasy = std::unique_ptr<CURL, EasyDeleter>;
using CurlMulti = std::unique_ptr<CURLM, MultiDeleter>;
using CurlList = std::unique_ptr<curl_slist, ListDeleter>;

// libcurl's global state, set up before the first handle and torn down at
// exit (curl_global_init is not thread-safe: a function-local static is).
void ensure_curl_initialised() {
    struct Global {
        Global() {
            if (curl_global_init(CURL_GLOBAL_DEFAULT) != CURLE_OK)
                throw ScannerError("libcurl: global initialisation failed");
        }
        ~Global() { curl_global_cleanup(); }
        Global(const Global&) = delete;
        Global& operator=(const Global&) = delete;
    };
    static const Global global;
}

// Error bodies are short JSON; more than this is not worth keeping.
constexpr std::size_t max_error_body = 64 * 1024;

const char* reason_phrase(long status) {
    switch (status) {
    case 400:
        return "Bad Request";
    case 401:
        return "Unauthorized";
    case 403:
        return "Forbidden";
    case 404:
        return "Not Found";
    case 405:
        return "Method Not Allowed";
    case 409:
        return "Conflict";
    case 413:
        return "Content Too Large";
    case 431:
        return "Request Header Fields Too Large";
    case 500:
        return "Internal Server Error";
    case 503:
        return "Service Unavailable";
    default:
        return "";
    }
}

// "METHOD URL: HTTP 409 Conflict: <the scanner's error text>".
ScannerError http_error(const std::string& what, long status, const std::string& body) {
    std::string message = what + ": HTTP " + std::to_string(status);
    if (*reason_phrase(status))
        message += std::string(" ") + reason_phrase(status);
    std::string why;
    const auto json = nlohmann::json::parse(body, nullptr, /*allow_exceptions=*/false);
    if (json.is_object() && json.contains("error") && json["error"].is_string())
        why = json["error"].get<std::string>();
    else
        why = body.substr(0, 300);
    while (!why.empty() && (why.back() == '\n' || why.back() == '\r'))
        why.pop_back();
    message += why.empty() ? std::string(" (no error text)") : ": " + why;
    if (status == 401)
        message += " (the token is not the scanner's)";
    return ScannerError(message, status);
}

// "METHOD URL: <libcurl's reason>", for an answer that never came.
ScannerError transfer_error(const std::string& what, CURLcode code, const char* error_buffer) {
    std::string message = what + ": " + (*error_buffer ? error_buffer : curl_easy_strerror(code));
    if (code == CURLE_COULDNT_CONNECT || code == CURLE_COULDNT_RESOLVE_HOST)
        message += " (is fpp-scanner running there with its HTTP API on?)";
    return ScannerError(message);
}

template <typename T> void set_option(CURL* easy, CURLoption option, T value) {
    const CURLcode code = curl_easy_setopt(easy, option, value);
    if (code != CURLE_OK)
        throw ScannerError(std::string("libcurl: cannot set option ") + std::to_string(option) +
                           ": " + curl_easy_strerror(code));
}

// Where the answer's body goes: `on_success` for a 2xx answer, kept as the
// error text otherwise. An exception in `on_success` (a full disk) stops
// the transfer and is rethrown after it.
struct BodySink {
    CURL* easy = nullptr;
    std::function<void(std::string_view)> on_success;
    std::string error_body;
    std::exception_ptr failure;

    long status() const {
        long code = 0;
        curl_easy_getinfo(easy, CURLINFO_RESPONSE_CODE, &code);
        return code;
    }
    bool take(std::string_view bytes) {
        try {
            const long code = status();
            if (code >= 200 && code < 300)
                on_success(bytes);
            else if (error_body.size() < max_error_body)
                error_body.append(bytes.substr(0, max_error_body - error_body.size()));
            return true;
        } catch (...) {
            failure = std::current_exception();
            return false;
        }
    }
};

size_t write_to_sink(char* data, size_t size, size_t count, void* user) {
    const size_t bytes = size * count;
    return static_cast<BodySink*>(user)->take({data, bytes}) ? bytes : 0;
}

// An upload body read from memory.
size_t read_from_view(char* buffer, size_t size, size_t count, void* user) {
    auto& rest = *static_cast<std::string_view*>(user);
    const size_t n = std::min(size * count, rest.size());
    std::copy_n(rest.data(), n, buffer);
    rest.remove_prefix(n);
    return n;
}

// One request: its handle, headers and error buffer, which libcurl reads
// until the handle is cleaned up.
struct Request {
    std::string what; // "METHOD URL", for messages
    CurlList headers;
    CurlEasy easy;
    char error_buffer[CURL_ERROR_SIZE] = {};
    BodySink sink;

    Request(const std::string& method, const std::string& url, const std::string& token,
            const std::vector<std::string>& extra_headers)
        : what(method + " " + url) {
        ensure_curl_initialised();
        easy.reset(curl_easy_init());
        if (!easy)
            throw ScannerError(what + ": libcurl: cannot create a handle");
        for (const std::string& header : extra_headers)
            append_header(header);
        append_header("Authorization: Bearer " + token);
        CURL* e = easy.get();
        set_option(e, CURLOPT_URL, url.c_str());
        set_option(e, CURLOPT_PROTOCOLS_STR, "http,https");
        set_option(e, CURLOPT_HTTPHEADER, headers.get());
        set_option(e, CURLOPT_ERRORBUFFER, error_buffer);
        set_option(e, CURLOPT_USERAGENT, "fpp-calib/0.1.0");
        set_option(e, CURLOPT_NOSIGNAL, 1L); // no SIGALRM for timeouts; safe with threads
        // A scanner that is not there should say so quickly...
        set_option(e, CURLOPT_CONNECTTIMEOUT_MS, 5000L);
        // ...but a session's tar may take minutes: a stalled transfer (under
        // 1 byte/s for a minute) fails rather than a slow one.
        set_option(e, CURLOPT_LOW_SPEED_LIMIT, 1L);
        set_option(e, CURLOPT_LOW_SPEED_TIME, 60L);
        if (method != "GET" && method != "POST" && method != "PUT")
            set_option(e, CURLOPT_CUSTOMREQUEST, method.c_str());
        sink.easy = e;
        set_option(e, CURLOPT_WRITEFUNCTION, write_to_sink);
        set_option(e, CURLOPT_WRITEDATA, &sink);
    }

    void append_header(const std::string& header) {
        curl_slist* list = curl_slist_append(headers.get(), header.c_str());
        if (!list)
            throw ScannerError(what + ": libcurl: out of memory for headers");
        (void)headers.release(); // now owned through `list`
        headers.reset(list);
    }

    // Runs the request; throws unless the answer is 2xx.
    void perform() {
        const CURLcode code = curl_easy_perform(easy.get());
        if (sink.failure)
            std::rethrow_exception(sink.failure);
        if (code != CURLE_OK)
            throw transfer_error(what, code, error_buffer);
        const long status = sink.status();
        if (status < 200 || status >= 300)
            throw http_error(what, status, sink.error_body);
    }
};

nlohmann::json parse_json_answer(const std::string& what, const std::string& body) {
    if (body.empty())
        return nullptr;
    try {
        return nlohmann::json::parse(body);
    } catch (const nlohmann::json::parse_error& e) {
        throw ScannerError(what + ": the answer is not JSON (" + e.what() + ")");
    }
}

bool is_token_character(char c) {
    return c > ' ' && c < 127;
}

void check_token(const std::string& token, const std::string& source) {
    if (token.size() < 16 || token.size() > 256 ||
        !std::all_of(token.begin(), token.end(), is_token_character))
        throw InputError(source, "token",
                         "expected 16 to 256 printable ASCII characters without spaces, got " +
                             std::to_string(token.size()) + " characters");
}

} // namespace

std::string read_scanner_token(const std::filesystem::path& token_file) {
    std::ifstream in(token_file, std::ios::binary);
    if (!in)
        throw InputError(token_file, "", "cannot read the token file");
    std::string token;
    std::getline(in, token);
    if (!token.empty() && token.back() == '\r')
        token.pop_back();
    check_token(token, token_file.string());
    return token;
}

ScannerClient::ScannerClient(std::string base_url, std::string token)
    : base_url_(std::move(base_url)), token_(std::move(token)) {
    while (!base_url_.empty() && base_url_.back() == '/')
        base_url_.pop_back();
    const auto scheme_end = base_url_.find("://");
    const std::string scheme = base_url_.substr(0, scheme_end);
    if (scheme_end == std::string::npos || (scheme != "http" && scheme != "https") ||
        base_url_.size() == scheme_end + 3)
        throw std::invalid_argument("scanner address \"" + base_url_ +
                                    "\": expected http://HOST:PORT");
    check_token(token_, "the scanner's API token");
}

nlohmann::json ScannerClient::get_json(std::string_view path) const {
    Request request("GET", url(path), token_, {"Accept: application/json"});
    std::string body;
    request.sink.on_success = [&](std::string_view bytes) { body.append(bytes); };
    request.perform();
    return parse_json_answer(request.what, body);
}

nlohmann::json ScannerClient::post_json(std::string_view path, const nlohmann::json& body) const {
    Request request("POST", url(path), token_,
                    {"Accept: application/json", "Content-Type: application/json"});
    const std::string text = body.is_null() ? std::string() : body.dump();
    set_option(request.easy.get(), CURLOPT_POSTFIELDSIZE_LARGE, curl_off_t(text.size()));
    set_option(request.easy.get(), CURLOPT_POSTFIELDS, text.c_str());
    std::string answer;
    request.sink.on_success = [&](std::string_view bytes) { answer.append(bytes); };
    request.perform();
    return parse_json_answer(request.what, answer);
}

nlohmann::json ScannerClient::put_bytes(std::string_view path, std::string_view bytes) const {
    Request request("PUT", url(path), token_,
                    {"Accept: application/json", "Content-Type: application/octet-stream"});
    std::string_view rest = bytes;
    CURL* e = request.easy.get();
    set_option(e, CURLOPT_UPLOAD, 1L);
    set_option(e, CURLOPT_INFILESIZE_LARGE, curl_off_t(bytes.size()));
    set_option(e, CURLOPT_READFUNCTION, read_from_view);
    set_option(e, CURLOPT_READDATA, &rest);
    std::string answer;
    request.sink.on_success = [&](std::string_view part) { answer.append(part); };
    request.perform();
    return parse_json_answer(request.what, answer);
}

std::uint64_t ScannerClient::download(std::string_view path,
                                      const std::filesystem::path& target) const {
    std::uint64_t total = 0;
    write_atomically(target, [&](const std::filesystem::path& temp) {
        Request request("GET", url(path), token_, {});
        SyncedFileWriter out(temp);
        request.sink.on_success = [&](std::string_view bytes) {
            out.write(bytes);
            total += bytes.size();
        };
        request.perform();
        out.finish();
    });
    return total;
}

// ---- the event stream ----------------------------------------------------

struct ScannerEventStream::Transfer {
    std::string what;
    CurlMulti multi;
    CurlList headers;
    CurlEasy easy;
    char error_buffer[CURL_ERROR_SIZE] = {};
    BodySink sink;
    ServerSentEventParser parser;
    std::vector<ServerEvent> parsed;
    std::deque<ServerEvent> ready;
    std::chrono::steady_clock::time_point last_bytes = std::chrono::steady_clock::now();
    bool done = false;
    CURLcode result = CURLE_OK;

    Transfer() = default;
    Transfer(const Transfer&) = delete;
    Transfer& operator=(const Transfer&) = delete;
    ~Transfer() {
        if (multi && easy)
            curl_multi_remove_handle(multi.get(), easy.get());
    }

    // Why the stream stopped, as an exception.
    ScannerError ended() const {
        if (result != CURLE_OK)
            return transfer_error(what, result, error_buffer);
        const long status = sink.status();
        if (status < 200 || status >= 300)
            return http_error(what, status, sink.error_body);
        return ScannerError(what + ": the scanner closed the event stream");
    }
};

ScannerEventStream ScannerClient::events() const {
    // The handle is set up as any request's, then handed to a multi handle
    // so that the transfer advances only while the caller waits for events.
    Request request("GET", url("/api/v1/events"), token_, {"Accept: text/event-stream"});
    auto transfer = std::make_unique<ScannerEventStream::Transfer>();
    transfer->what = request.what;
    transfer->headers = std::move(request.headers);
    transfer->easy = std::move(request.easy);
    CURL* e = transfer->easy.get();
    // The stream is quiet between scans: the silence limit in next() (the
    // keep-alive comes every 10 s) replaces the low-speed limit.
    set_option(e, CURLOPT_LOW_SPEED_LIMIT, 0L);
    set_option(e, CURLOPT_ERRORBUFFER, transfer->error_buffer);
    transfer->sink.easy = e;
    ScannerEventStream::Transfer* t = transfer.get();
    transfer->sink.on_success = [t](std::string_view bytes) {
        t->last_bytes = std::chrono::steady_clock::now();
        t->parser.feed(bytes, t->parsed);
        for (ServerEvent& event : t->parsed)
            t->ready.push_back(std::move(event));
        t->parsed.clear();
    };
    set_option(e, CURLOPT_WRITEDATA, &transfer->sink);
    transfer->multi.reset(curl_multi_init());
    if (!transfer->multi || curl_multi_add_handle(transfer->multi.get(), e) != CURLM_OK)
        throw ScannerError(transfer->what + ": libcurl: cannot start the transfer");
    return ScannerEventStream(std::move(transfer));
}

ScannerEventStream::ScannerEventStream(std::unique_ptr<Transfer> transfer)
    : transfer_(std::move(transfer)) {}
ScannerEventStream::~ScannerEventStream() = default;
ScannerEventStream::ScannerEventStream(ScannerEventStream&&) noexcept = default;
ScannerEventStream& ScannerEventStream::operator=(ScannerEventStream&&) noexcept = default;

std::optional<ServerEvent> ScannerEventStream::next(std::chrono::milliseconds timeout) {
    using clock = std::chrono::steady_clock;
    Transfer& t = *transfer_;
    const auto deadline = clock::now() + timeout;
    for (;;) {
        if (!t.ready.empty()) {
            ServerEvent event = std::move(t.ready.front());
            t.ready.pop_front();
            return event;
        }
        if (t.done)
            throw t.ended();
        int running = 0;
        const CURLMcode code = curl_multi_perform(t.multi.get(), &running);
        if (code != CURLM_OK)
            throw ScannerError(t.what + ": libcurl: " + curl_multi_strerror(code));
        if (t.sink.failure)
            std::rethrow_exception(t.sink.failure);
        int left = 0;
        while (CURLMsg* message = curl_multi_info_read(t.multi.get(), &left)) {
            if (message->msg == CURLMSG_DONE) {
                t.done = true;
                t.result = message->data.result;
            }
        }
        if (!t.ready.empty() || t.done)
            continue;
        const auto now = clock::now();
        if (now - t.last_bytes > silence_limit)
            throw ScannerError(t.what + ": nothing from the scanner for " +
                               std::to_string(silence_limit.count()) +
                               " s (not even its keep-alive)");
        if (now >= deadline)
            return std::nullopt;
        const auto wait =
            std::min(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now),
                     std::chrono::milliseconds(1000));
        curl_multi_poll(t.multi.get(), nullptr, 0, static_cast<int>(wait.count()) + 1, nullptr);
    }
}

} // namespace fpp::calib
