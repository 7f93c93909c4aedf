// The server-sent events' hub (fpp/scanner/event_hub.hpp): the wire text, a
// stream's first event, every stream its own queue, the oldest events
// dropped for a stream that does not read, the timeout, and shutdown.
#include <gtest/gtest.h>

#include "fpp/scanner/event_hub.hpp"

#include <chrono>
#include <string>

using fpp::scanner::EventHub;
using namespace std::chrono_literals;

TEST(EventHub, FormatIsTheSseWireText) {
    EXPECT_EQ(EventHub::format("state", R"({"state":"idle"})"),
              "event: state\ndata: {\"state\":\"idle\"}\n\n");
}

TEST(EventHub, AStreamStartsWithItsFirstEventThenGetsEveryPublishedOne) {
    EventHub hub;
    const auto stream = hub.subscribe(EventHub::format("state", "{}"));
    hub.publish("written", R"({"id":"a"})");
    hub.publish("written", R"({"id":"b"})");
    EXPECT_EQ(stream->next(10ms), "event: state\ndata: {}\n\n");
    EXPECT_EQ(stream->next(10ms), "event: written\ndata: {\"id\":\"a\"}\n\n");
    EXPECT_EQ(stream->next(10ms), "event: written\ndata: {\"id\":\"b\"}\n\n");
    // Nothing more: an empty string after the timeout (the keep-alive's turn).
    EXPECT_EQ(stream->next(10ms), "");
}

TEST(EventHub, EveryStreamHasItsOwnQueue) {
    EventHub hub;
    const auto first = hub.subscribe("");
    hub.publish("decoded", R"({"id":"a"})");
    const auto second = hub.subscribe(""); // after the first event: does not get it
    hub.publish("written", R"({"id":"a"})");
    EXPECT_EQ(hub.subscribers(), 2u);
    EXPECT_EQ(first->next(10ms), EventHub::format("decoded", R"({"id":"a"})"));
    EXPECT_EQ(first->next(10ms), EventHub::format("written", R"({"id":"a"})"));
    EXPECT_EQ(second->next(10ms), EventHub::format("written", R"({"id":"a"})"));
    EXPECT_EQ(second->next(10ms), "");
}

TEST(EventHub, AStreamThatDoesNotReadLosesItsOldestEventsNotTheNewest) {
    EventHub hub;
    const auto slow = hub.subscribe("");
    const std::size_t published = EventHub::kQueueLength + 40;
    for (std::size_t i = 0; i < published; ++i)
        hub.publish("frame-captured", "{\"frame\":" + std::to_string(i) + "}");
    std::size_t received = 0;
    std::string first, last;
    for (auto next = slow->next(10ms); next && !next->empty(); next = slow->next(10ms)) {
        if (received++ == 0)
            first = *next;
        last = *next;
    }
    EXPECT_EQ(received, EventHub::kQueueLength);
    EXPECT_EQ(first, EventHub::format("frame-captured", "{\"frame\":40}"));
    EXPECT_EQ(last, EventHub::format("frame-captured",
                                     "{\"frame\":" + std::to_string(published - 1) + "}"));
}

TEST(EventHub, ClosingEndsEveryStreamAndLaterOnesAtOnce) {
    EventHub hub;
    const auto stream = hub.subscribe("");
    hub.close();
    EXPECT_EQ(stream->next(1000ms), std::nullopt);
    // A stream opened after shutdown gets its first event (the state), then ends.
    const auto late = hub.subscribe(EventHub::format("state", "{}"));
    EXPECT_EQ(late->next(1000ms), EventHub::format("state", "{}"));
    EXPECT_EQ(late->next(1000ms), std::nullopt);
    hub.publish("written", "{}"); // no stream, no effect
}

TEST(EventHub, AStreamNobodyHoldsIsForgotten) {
    EventHub hub;
    auto stream = hub.subscribe("");
    EXPECT_EQ(hub.subscribers(), 1u);
    stream.reset();
    hub.publish("state", "{}");
    EXPECT_EQ(hub.subscribers(), 0u);
}
