#pragma once
// Server-sent events: the scanner publishes, every open /events stream gets
// its own bounded queue. A stream that reads too slowly loses its oldest
// events instead of slowing the scan down.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace fpp::scanner {

class EventHub {
public:
    static constexpr std::size_t kQueueLength = 256;

    class Subscription {
    public:
        // The next event as SSE text ("event: NAME\ndata: JSON\n\n"), or an
        // empty string after `timeout` with nothing to send, or nullopt once
        // the hub is closed.
        std::optional<std::string> next(std::chrono::milliseconds timeout);

    private:
        friend class EventHub;
        void push(const std::string& text);
        void close();
        std::mutex mutex_;
        std::condition_variable ready_;
        std::deque<std::string> queue_;
        bool closed_ = false;
    };

    // A new stream, starting with `first` (already SSE text; may be empty).
    std::shared_ptr<Subscription> subscribe(const std::string& first);

    // `data` must be one line of JSON.
    void publish(const std::string& event, const std::string& data);

    // Ends every stream (shutdown); later subscriptions are closed at once.
    void close();

    std::size_t subscribers();

    static std::string format(const std::string& event, const std::string& data);

private:
    std::mutex mutex_;
    std::vector<std::weak_ptr<Subscription>> subscribers_;
    bool closed_ = false;
};

} // namespace fpp::scanner
