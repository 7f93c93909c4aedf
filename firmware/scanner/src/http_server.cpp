#include "fpp/scanner/http_server.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"

#include <nlohmann/json.hpp>

#include <microhttpd.h>

#include <arpa/inet.h>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fpp::scanner {

namespace fs = std::filesystem;

HttpResponse HttpResponse::json(int status, std::string body) {
    HttpResponse r;
    r.status = status;
    r.body = std::move(body);
    return r;
}

HttpResponse HttpResponse::no_content() {
    HttpResponse r;
    r.status = 204;
    return r;
}

HttpResponse HttpResponse::error(int status, const std::string& message) {
    // The message may quote the request (a field name, a parse error at a
    // byte): bytes that are not UTF-8 become U+FFFD instead of failing the
    // dump, which would turn a 400 into a 500.
    return json(status, nlohmann::json{{"error", message}}.dump(
                            -1, ' ', false, nlohmann::json::error_handler_t::replace));
}

struct HttpServer::Context {
    HttpHandler& handler;
    const Logger& log;
    HttpServerOptions options;
};

namespace {

// One request's state across libmicrohttpd's calls (headers, each piece of
// the body, the end); freed when the request completes. A spooled body
// file that the handler did not take is removed then.
struct RequestContext {
    HttpRequest request;
    BodyPolicy policy;
    int spool_fd = -1;
    // A 413 or 507 decided mid-body, sent when the body ends: libmicrohttpd
    // (0.9.75) queues no response while a body is still arriving, so the
    // rest is read and dropped, at most `kMaxDiscard` bytes of it.
    std::optional<HttpResponse> refusal;
    std::uint64_t discarded = 0;
    ~RequestContext() {
        if (spool_fd >= 0)
            ::close(spool_fd);
        if (!request.body_file.empty())
            ::unlink(request.body_file.c_str());
    }
};

using ServerContext = HttpServer::Context;

// The most of a refused body read and dropped before its answer; a body that
// goes on longer loses its connection instead.
constexpr std::uint64_t kMaxDiscard = 8u << 20;

std::string header(MHD_Connection* c, const char* name) {
    const char* v = MHD_lookup_connection_value(c, MHD_HEADER_KIND, name);
    return v ? v : "";
}

ssize_t read_stream(void* cls, std::uint64_t, char* buf, std::size_t max) {
    auto& stream = *static_cast<std::shared_ptr<HttpStream>*>(cls);
    try {
        const std::size_t n = stream->read(buf, max);
        return n == 0 ? MHD_CONTENT_READER_END_OF_STREAM : static_cast<ssize_t>(n);
    } catch (...) {
        return MHD_CONTENT_READER_END_WITH_ERROR;
    }
}

void free_stream(void* cls) {
    delete static_cast<std::shared_ptr<HttpStream>*>(cls);
}

MHD_Response* make_response(HttpResponse& r) {
    if (r.stream) {
        auto* holder = new std::shared_ptr<HttpStream>(std::move(r.stream));
        MHD_Response* m = MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 64 * 1024,
                                                            &read_stream, holder, &free_stream);
        if (!m)
            free_stream(holder);
        return m;
    }
    if (r.file) {
        const int fd = ::open(r.file->c_str(), O_RDONLY | O_CLOEXEC);
        struct stat st {};
        if (fd >= 0 && ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode))
            // libmicrohttpd owns the descriptor from here and closes it.
            return MHD_create_response_from_fd64(static_cast<std::uint64_t>(st.st_size), fd);
        if (fd >= 0)
            ::close(fd);
        r = HttpResponse::error(404, "no such file");
    }
    return MHD_create_response_from_buffer(r.body.size(), r.body.data(), MHD_RESPMEM_MUST_COPY);
}

MHD_Result queue(MHD_Connection* connection, HttpResponse r) {
    MHD_Response* m = make_response(r);
    if (!m)
        return MHD_NO;
    MHD_add_response_header(m, MHD_HTTP_HEADER_CONTENT_TYPE, r.content_type.c_str());
    MHD_add_response_header(m, "X-Content-Type-Options", "nosniff");
    MHD_add_response_header(m, "Referrer-Policy", "no-referrer");
    for (const auto& [name, value] : r.headers)
        MHD_add_response_header(m, name.c_str(), value.c_str());
    const MHD_Result result = MHD_queue_response(connection, static_cast<unsigned>(r.status), m);
    MHD_destroy_response(m);
    return result;
}

MHD_Result add_field_bytes(void* cls, MHD_ValueKind, const char* key, const char* value) {
    *static_cast<std::size_t*>(cls) += std::strlen(key) + (value ? std::strlen(value) : 0) + 4;
    return MHD_YES;
}

// A request target or header block longer than the options allow, answered
// as JSON (longer than the connection's memory, libmicrohttpd answers itself).
std::optional<HttpResponse> too_long(MHD_Connection* connection, const char* url,
                                     const HttpServerOptions& options) {
    const std::size_t target = std::strlen(url);
    if (target > options.max_target)
        return HttpResponse::error(414, "the request target is " + std::to_string(target) +
                                            " bytes, at most " +
                                            std::to_string(options.max_target) + " are taken");
    std::size_t fields = 0;
    MHD_get_connection_values(connection, MHD_HEADER_KIND, &add_field_bytes, &fields);
    if (fields > options.max_headers)
        return HttpResponse::error(431, "the header fields are " + std::to_string(fields) +
                                            " bytes, at most " +
                                            std::to_string(options.max_headers) + " are taken");
    return std::nullopt;
}

// Appends a piece of the body; otherwise the answer to give at once (413
// over the policy's limit, 507 when the spool file cannot take it).
std::optional<HttpResponse> take_body(RequestContext& ctx, const char* data, std::size_t size) {
    if (ctx.request.body_bytes + size > ctx.policy.max_bytes)
        return HttpResponse::error(413, "the body passed " + std::to_string(ctx.policy.max_bytes) +
                                            " bytes, at most that many are taken here");
    ctx.request.body_bytes += size;
    if (ctx.spool_fd < 0) {
        ctx.request.body.append(data, size);
        return std::nullopt;
    }
    while (size > 0) {
        const ssize_t n = ::write(ctx.spool_fd, data, size);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return HttpResponse::error(
                507, describe_errno("cannot store the upload", n < 0 ? errno : ENOSPC));
        data += n;
        size -= static_cast<std::size_t>(n);
    }
    return std::nullopt;
}

bool open_spool(RequestContext& ctx) {
    std::string name = (*ctx.policy.spool_dir / ".upload-XXXXXX").string();
    ctx.spool_fd = ::mkostemp(name.data(), O_CLOEXEC);
    if (ctx.spool_fd < 0)
        return false;
    ctx.request.body_file = name;
    return true;
}

MHD_Result on_request(void* cls, MHD_Connection* connection, const char* url, const char* method,
                      const char*, const char* upload_data, std::size_t* upload_data_size,
                      void** con_cls) {
    auto& server = *static_cast<ServerContext*>(cls);
    try {
        if (*con_cls == nullptr) {
            auto ctx = std::make_unique<RequestContext>();
            ctx->request.method = method;
            ctx->request.path = url;
            ctx->request.authorization = header(connection, MHD_HTTP_HEADER_AUTHORIZATION);
            ctx->request.content_type = header(connection, MHD_HTTP_HEADER_CONTENT_TYPE);
            ctx->request.if_none_match = header(connection, MHD_HTTP_HEADER_IF_NONE_MATCH);
            std::optional<HttpResponse> early = too_long(connection, url, server.options);
            if (!early)
                early = server.handler.begin(ctx->request, ctx->policy);
            if (!early) {
                const std::string length = header(connection, MHD_HTTP_HEADER_CONTENT_LENGTH);
                if (!length.empty() &&
                    std::strtoull(length.c_str(), nullptr, 10) > ctx->policy.max_bytes)
                    early = HttpResponse::error(413, "the body is " + length + " bytes, at most " +
                                                         std::to_string(ctx->policy.max_bytes) +
                                                         " are taken here");
                else if (ctx->policy.spool_dir && !open_spool(*ctx))
                    early =
                        HttpResponse::error(507, describe_errno("cannot store the upload in " +
                                                                    ctx->policy.spool_dir->string(),
                                                                errno));
            }
            RequestContext* raw = ctx.release();
            *con_cls = raw;
            if (early)
                return queue(connection, std::move(*early));
            return MHD_YES;
        }
        auto& ctx = *static_cast<RequestContext*>(*con_cls);
        if (*upload_data_size > 0) {
            const std::size_t size = *upload_data_size;
            *upload_data_size = 0;
            if (ctx.refusal) {
                ctx.discarded += size;
                if (ctx.discarded <= kMaxDiscard)
                    return MHD_YES;
                server.log.warning("http: " + ctx.request.method + " " + ctx.request.path +
                                   ": body goes on " + std::to_string(kMaxDiscard) +
                                   " bytes past its refusal: connection dropped");
                return MHD_NO;
            }
            ctx.refusal = take_body(ctx, upload_data, size);
            if (ctx.refusal)
                server.log.warning("http: " + ctx.request.method + " " + ctx.request.path + ": " +
                                   std::to_string(ctx.refusal->status) + " after " +
                                   std::to_string(ctx.request.body_bytes) +
                                   " bytes; the rest of the body is dropped");
            return MHD_YES;
        }
        if (ctx.refusal)
            return queue(connection, std::move(*ctx.refusal));
        if (ctx.spool_fd >= 0) {
            const bool synced = ::fsync(ctx.spool_fd) == 0;
            ::close(ctx.spool_fd);
            ctx.spool_fd = -1;
            if (!synced)
                return queue(
                    connection,
                    HttpResponse::error(507, describe_errno("cannot store the upload", errno)));
        }
        return queue(connection, server.handler.handle(ctx.request));
    } catch (const std::exception& e) {
        server.log.error(std::string("http: ") + method + " " + url + ": " + e.what());
        return queue(connection, HttpResponse::error(500, e.what()));
    }
}

// Percent escapes decoded as libmicrohttpd does, except in a URL holding an
// escaped NUL ("%00"), which is left as it came: decoded, the NUL would end
// the C string the handler gets and cut the path short
// ("/api/v1/scans/ID%00/x" would name the scan ID), so it stays a path that
// names nothing (404).
std::size_t unescape(void*, MHD_Connection*, char* s) {
    if (std::strstr(s, "%00"))
        return std::strlen(s);
    return MHD_http_unescape(s);
}

void on_completed(void*, MHD_Connection*, void** con_cls, MHD_RequestTerminationCode) {
    delete static_cast<RequestContext*>(*con_cls);
    *con_cls = nullptr;
}

void on_log(void* cls, const char* format, va_list args) {
    char text[512];
    std::vsnprintf(text, sizeof text, format, args);
    std::string line(text);
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r'))
        line.pop_back();
    static_cast<ServerContext*>(cls)->log.warning("http: " + line);
}

// The listening socket, made here so that errors name the address and port
// 0 can be read back. libmicrohttpd closes it when it stops.
int listen_on(const std::string& host, int port, int& bound_port, bool& ipv6) {
    std::string literal = host;
    if (literal.size() > 2 && literal.front() == '[' && literal.back() == ']')
        literal = literal.substr(1, literal.size() - 2);
    sockaddr_storage address{};
    socklen_t length = 0;
    auto* v4 = reinterpret_cast<sockaddr_in*>(&address);
    auto* v6 = reinterpret_cast<sockaddr_in6*>(&address);
    const std::string where = host + ":" + std::to_string(port);
    if (::inet_pton(AF_INET, literal.c_str(), &v4->sin_addr) == 1) {
        v4->sin_family = AF_INET;
        v4->sin_port = htons(static_cast<std::uint16_t>(port));
        length = sizeof *v4;
        ipv6 = false;
    } else if (::inet_pton(AF_INET6, literal.c_str(), &v6->sin6_addr) == 1) {
        v6->sin6_family = AF_INET6;
        v6->sin6_port = htons(static_cast<std::uint16_t>(port));
        length = sizeof *v6;
        ipv6 = true;
    } else {
        throw IoError(where, "not an IPv4 or IPv6 address");
    }
    const int fd = ::socket(address.ss_family, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0)
        throw IoError(where, describe_errno("socket", errno));
    const int on = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    if (::bind(fd, reinterpret_cast<sockaddr*>(&address), length) != 0 || ::listen(fd, 64) != 0) {
        const int err = errno;
        ::close(fd);
        throw IoError(where, describe_errno("cannot listen", err));
    }
    length = sizeof address;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
    bound_port = ntohs(ipv6 ? v6->sin6_port : v4->sin_port);
    return fd;
}

} // namespace

void HttpServer::DaemonStop::operator()(MHD_Daemon* d) const {
    MHD_stop_daemon(d);
}

HttpServer::HttpServer(const HttpServerOptions& options, HttpHandler& handler, const Logger& log)
    : options_(options), context_(new Context{handler, log, options}) {
    bool ipv6 = false;
    const int fd = listen_on(options.host, options.port, port_, ipv6);
    unsigned flags = MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_THREAD_PER_CONNECTION |
                     MHD_USE_POLL | MHD_USE_ERROR_LOG;
    if (ipv6)
        flags |= MHD_USE_IPv6;
    MHD_Daemon* d = MHD_start_daemon(
        flags, 0, nullptr, nullptr, &on_request, context_.get(), MHD_OPTION_EXTERNAL_LOGGER,
        &on_log, context_.get(), MHD_OPTION_LISTEN_SOCKET, fd, MHD_OPTION_CONNECTION_LIMIT,
        static_cast<unsigned>(options.max_connections), MHD_OPTION_CONNECTION_TIMEOUT,
        static_cast<unsigned>(options.timeout.count()), MHD_OPTION_CONNECTION_MEMORY_LIMIT,
        options.connection_memory, MHD_OPTION_NOTIFY_COMPLETED, &on_completed, nullptr,
        MHD_OPTION_UNESCAPE_CALLBACK, &unescape, nullptr, MHD_OPTION_END);
    if (!d) {
        ::close(fd);
        throw IoError(address(), "the HTTP server did not start (libmicrohttpd)");
    }
    daemon_.reset(d);
}

HttpServer::~HttpServer() = default;

std::string HttpServer::address() const {
    return options_.host + ":" + std::to_string(port_);
}

} // namespace fpp::scanner
