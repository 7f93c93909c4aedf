#include "fpp/scanner/event_hub.hpp"

#include <algorithm>

namespace fpp::scanner {

std::optional<std::string> EventHub::Subscription::next(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    ready_.wait_for(lock, timeout, [&] { return closed_ || !queue_.empty(); });
    if (!queue_.empty()) {
        std::string text = std::move(queue_.front());
        queue_.pop_front();
        return text;
    }
    if (closed_)
        return std::nullopt;
    return std::string();
}

void EventHub::Subscription::push(const std::string& text) {
    {
        const std::lock_guard lock(mutex_);
        if (queue_.size() == kQueueLength)
            queue_.pop_front();
        queue_.push_back(text);
    }
    ready_.notify_one();
}

void EventHub::Subscription::close() {
    {
        const std::lock_guard lock(mutex_);
        closed_ = true;
    }
    ready_.notify_all();
}

std::string EventHub::format(const std::string& event, const std::string& data) {
    return "event: " + event + "\ndata: " + data + "\n\n";
}

std::shared_ptr<EventHub::Subscription> EventHub::subscribe(const std::string& first) {
    auto s = std::make_shared<Subscription>();
    if (!first.empty())
        s->push(first);
    const std::lock_guard lock(mutex_);
    if (closed_)
        s->close();
    // Streams that ended leave expired entries: drop them as new ones come.
    std::erase_if(subscribers_, [](const auto& w) { return w.expired(); });
    subscribers_.push_back(s);
    return s;
}

void EventHub::publish(const std::string& event, const std::string& data) {
    const std::string text = format(event, data);
    const std::lock_guard lock(mutex_);
    for (const auto& w : subscribers_)
        if (auto s = w.lock())
            s->push(text);
}

void EventHub::close() {
    const std::lock_guard lock(mutex_);
    closed_ = true;
    for (const auto& w : subscribers_)
        if (auto s = w.lock())
            s->close();
}

std::size_t EventHub::subscribers() {
    const std::lock_guard lock(mutex_);
    return static_cast<std::size_t>(std::count_if(subscribers_.begin(), subscribers_.end(),
                                                  [](const auto& w) { return !w.expired(); }));
}

} // namespace fpp::scanner
