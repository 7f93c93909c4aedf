#pragma once
// A parser of server-sent events (text/event-stream, the WHATWG "event
// stream" format) as fpp-scanner's GET /api/v1/events sends them: blocks of
// `event: NAME` and `data: ...` lines ended by a blank line, comment lines
// (`: keep-alive`) ignored. Bytes go in as they arrive, cut anywhere.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace fpp::calib {

struct ServerEvent {
    std::string name = "message"; // the stream format's default when a block has no `event:`
    std::string data;             // `data:` lines joined by '\n'
};

class ServerSentEventParser {
public:
    // A longer line is an error rather than memory without bound.
    static constexpr std::size_t max_line_bytes = 1 << 20;

    // Appends to `out` every event that `bytes` completes. Throws
    // std::runtime_error for a line longer than max_line_bytes.
    void feed(std::string_view bytes, std::vector<ServerEvent>& out);

private:
    void take_line(std::string_view line, std::vector<ServerEvent>& out);

    std::string line_;    // the current line's bytes so far
    ServerEvent pending_; // the block being read
    bool has_data_ = false;
};

} // namespace fpp::calib
