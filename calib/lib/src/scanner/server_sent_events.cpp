#include "fpp/calib/server_sent_events.hpp"

#include <stdexcept>

namespace fpp::calib {

void ServerSentEventParser::feed(std::string_view bytes, std::vector<ServerEvent>& out) {
    while (!bytes.empty()) {
        const auto end = bytes.find('\n');
        const std::string_view piece = bytes.substr(0, end);
        if (line_.size() + piece.size() > max_line_bytes)
            throw std::runtime_error("event stream: a line longer than " +
                                     std::to_string(max_line_bytes) + " bytes");
        line_.append(piece);
        if (end == std::string_view::npos)
            return;
        std::string_view line = line_;
        if (!line.empty() && line.back() == '\r')
            line.remove_suffix(1);
        take_line(line, out);
        line_.clear();
        bytes.remove_prefix(end + 1);
    }
}

void ServerSentEventParser::take_line(std::string_view line, std::vector<ServerEvent>& out) {
    if (line.empty()) { // the blank line ends a block; one without data is no event
        if (has_data_)
            out.push_back(std::move(pending_));
        pending_ = ServerEvent{};
        has_data_ = false;
        return;
    }
    if (line.front() == ':') // a comment: the keep-alive
        return;
    const auto colon = line.find(':');
    const std::string_view field = line.substr(0, colon);
    std::string_view value =
        colon == std::string_view::npos ? std::string_view{} : line.substr(colon + 1);
    if (!value.empty() && value.front() == ' ')
        value.remove_prefix(1);
    if (field == "event") {
        pending_.name = value;
    } else if (field == "data") {
        if (has_data_)
            pending_.data += '\n';
        pending_.data += value;
        has_data_ = true;
    } // `id` and `retry` mean nothing to a client that does not reconnect
}

} // namespace fpp::calib
