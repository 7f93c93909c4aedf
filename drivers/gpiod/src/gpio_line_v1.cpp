// The line requests over the libgpiod 1.x API. The chip handle is owned by a
// unique_ptr closing it, the request by one releasing the line; the line
// object itself belongs to the chip.
#include "gpio_line.hpp"

#include <fpp/drivers/device_error.hpp>

#include <gpiod.h>

#include <cerrno>
#include <cstring>

namespace fpp::drivers::gpio_detail {
namespace {

struct ChipClose {
    void operator()(gpiod_chip* chip) const noexcept { gpiod_chip_close(chip); }
};
struct LineRelease {
    void operator()(gpiod_line* line) const noexcept { gpiod_line_release(line); }
};
using ChipPtr = std::unique_ptr<gpiod_chip, ChipClose>;
using RequestPtr = std::unique_ptr<gpiod_line, LineRelease>;

class LineV1 final : public Line {
public:
    LineV1(ChipPtr chip, const GpioLineConfig& config, const std::string& device,
           const std::string& consumer, bool output, bool initial_active)
        : Line(device, gpiod_chip_label(chip.get())), chip_(std::move(chip)) {
        gpiod_line* line = gpiod_chip_get_line(chip_.get(), config.offset);
        if (line == nullptr)
            throw DeviceError(DeviceKind::gpio, name(),
                              "no such line on the chip: " + std::string(std::strerror(errno)));
        const int flags = config.active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
        const int result =
            output ? gpiod_line_request_output_flags(line, consumer.c_str(), flags,
                                                     initial_active ? 1 : 0)
                   : gpiod_line_request_both_edges_events_flags(line, consumer.c_str(), flags);
        if (result != 0)
            throw DeviceError(DeviceKind::gpio, name(),
                              "cannot request the line (held by another process?): " +
                                  std::string(std::strerror(errno)));
        request_.reset(line);
    }

    void set(bool active) override {
        if (gpiod_line_set_value(request_.get(), active ? 1 : 0) != 0)
            throw DeviceError(DeviceKind::gpio, name(),
                              "cannot set the line: " + std::string(std::strerror(errno)));
    }

    std::optional<Edge> wait_edge(std::chrono::nanoseconds timeout) override {
        const auto ns = std::max<std::int64_t>(0, timeout.count());
        timespec ts{};
        ts.tv_sec = static_cast<time_t>(ns / 1'000'000'000);
        ts.tv_nsec = static_cast<long>(ns % 1'000'000'000);
        const int ready = gpiod_line_event_wait(request_.get(), &ts);
        // A signal (SIGTERM from systemd) ends the wait like a timeout: the
        // caller looks at its stop flag.
        if (ready < 0 && errno == EINTR)
            return std::nullopt;
        if (ready < 0)
            throw DeviceError(DeviceKind::gpio, name(),
                              "waiting for an edge failed: " + std::string(std::strerror(errno)));
        if (ready == 0)
            return std::nullopt;
        gpiod_line_event event{};
        if (gpiod_line_event_read(request_.get(), &event) != 0)
            throw DeviceError(DeviceKind::gpio, name(),
                              "reading an edge failed: " + std::string(std::strerror(errno)));
        Edge edge;
        edge.timestamp_ns = std::int64_t(event.ts.tv_sec) * 1'000'000'000 + event.ts.tv_nsec;
        edge.rising = event.event_type == GPIOD_LINE_EVENT_RISING_EDGE;
        return edge;
    }

private:
    // Declared in this order so that the request is released before the chip closes.
    ChipPtr chip_;
    RequestPtr request_;
};

// 1.x's lookup takes a path, "gpiochip0", "0" or a label.
ChipPtr open_chip(const std::string& chip, const std::string& name) {
    ChipPtr opened(gpiod_chip_open_lookup(chip.c_str()));
    if (!opened)
        throw DeviceError(DeviceKind::gpio, name,
                          "cannot open the chip: " + std::string(std::strerror(errno)));
    return opened;
}

} // namespace

std::unique_ptr<Line> open_output_line(const GpioLineConfig& config, const std::string& chip,
                                       const std::string& name, const std::string& consumer,
                                       bool initial_active) {
    return std::make_unique<LineV1>(open_chip(chip, name), config, name, consumer, true,
                                    initial_active);
}

std::unique_ptr<Line> open_edge_line(const GpioLineConfig& config, const std::string& chip,
                                     const std::string& name, const std::string& consumer) {
    return std::make_unique<LineV1>(open_chip(chip, name), config, name, consumer, false, false);
}

} // namespace fpp::drivers::gpio_detail
