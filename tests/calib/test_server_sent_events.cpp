// The parser of the scanner's event stream (fpp-calib's client of the HTTP
// API, calib/lib/src/scanner/server_sent_events.cpp): the same events whatever the
// blocks the network cuts the stream into.
#include "fpp/calib/server_sent_events.hpp"

#include <gtest/gtest.h>

#include <string>
#include <string_view>
#include <vector>

namespace {

TEST(ServerSentEvents, BlocksCutAnywhereGiveTheSameEvents) {
    const std::string stream =
        ": keep-alive\n\n"
        "event: state\ndata: {\"state\": \"idle\", \"error\": null}\n\n"
        "event: frame-captured\r\ndata: {\"id\": \"a\", \"frame\": 1}\r\n\r\n"
        "data: first\ndata: second\n\n"
        "event: no-data\n\n"
        "event: written\ndata:{\"id\": \"a\"}\n\n"
        "event: partial\ndata: x";
    for (std::size_t piece : {std::size_t(1), std::size_t(3), std::size_t(7), stream.size()}) {
        fpp::calib::ServerSentEventParser parser;
        std::vector<fpp::calib::ServerEvent> events;
        for (std::size_t at = 0; at < stream.size(); at += piece)
            parser.feed(std::string_view(stream).substr(at, piece), events);
        ASSERT_EQ(events.size(), 4u) << piece;
        EXPECT_EQ(events[0].name, "state");
        EXPECT_EQ(events[0].data, "{\"state\": \"idle\", \"error\": null}");
        EXPECT_EQ(events[1].name, "frame-captured");
        EXPECT_EQ(events[1].data, "{\"id\": \"a\", \"frame\": 1}");
        EXPECT_EQ(events[2].name, "message");
        EXPECT_EQ(events[2].data, "first\nsecond");
        EXPECT_EQ(events[3].name, "written");
        EXPECT_EQ(events[3].data, "{\"id\": \"a\"}");
    }
}

} // namespace
