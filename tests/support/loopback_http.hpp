#pragma once
// HTTP/1.1 requests to a scanner on loopback for tests, over a real socket:
// one request per connection (Connection: close), the bearer token sent.
// Throws fpp::IoError when the connection cannot be made; a reply cut short
// has status 0.
#include "fpp/error.hpp"
#include "fpp/unique_fd.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>

namespace fpp::test {

struct HttpReply {
    int status = 0;
    std::string body;
};

// Sends `request` as it is on a connection of its own and reads the
// answer to the end (the request must say Connection: close). Sending stops
// quietly if the server answers and closes before taking everything.
inline std::string raw_exchange(int port, const std::string& request) {
    UniqueFd fd(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0));
    if (!fd.valid())
        throw IoError("socket", std::strerror(errno));
    sockaddr_in at{};
    at.sin_family = AF_INET;
    at.sin_port = htons(static_cast<std::uint16_t>(port));
    at.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd.get(), reinterpret_cast<const sockaddr*>(&at), sizeof at) != 0)
        throw IoError("127.0.0.1:" + std::to_string(port), std::strerror(errno));
    for (std::size_t sent = 0; sent < request.size();) {
        const ssize_t n =
            ::send(fd.get(), request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
        if (n <= 0)
            break;
        sent += static_cast<std::size_t>(n);
    }
    std::string data;
    char buffer[4096];
    for (;;) {
        const ssize_t n = ::recv(fd.get(), buffer, sizeof buffer, 0);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            break;
        data.append(buffer, static_cast<std::size_t>(n));
    }
    return data;
}

// One request on its own connection (Connection: close), read to its end.
inline HttpReply http_request(int port, const std::string& method, const std::string& path,
                              const std::string& token, const std::string& body = {}) {
    const std::string data = raw_exchange(
        port, method + " " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" + "Authorization: Bearer " +
                  token + "\r\n" + "Content-Type: application/json\r\nContent-Length: " +
                  std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + body);
    HttpReply r;
    if (data.rfind("HTTP/1.1 ", 0) == 0 && data.size() > 12)
        r.status = std::stoi(data.substr(9, 3));
    const std::size_t head_end = data.find("\r\n\r\n");
    if (head_end != std::string::npos)
        r.body = data.substr(head_end + 4);
    return r;
}

} // namespace fpp::test
