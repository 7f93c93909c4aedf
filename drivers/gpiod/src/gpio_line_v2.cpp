// The line requests over the libgpiod 2.x API (Debian 13, Raspberry Pi OS).
// Every C handle is owned by a unique_ptr freeing it; the settings and
// configs live only while the request is made, and the request outlives the
// chip (2.x requests hold their own file descriptor). Errors and messages are
// those of gpio_line_v1.cpp, so that a board file's mistake reads the same
// whichever libgpiod the scanner was built with.
#include "gpio_line.hpp"

#include <fpp/drivers/device_error.hpp>

#include <gpiod.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <new>
#include <string_view>
#include <sys/stat.h>

namespace fpp::drivers::gpio_detail {
namespace {

template <typename T, void (*Free)(T*)> struct Deleter {
    void operator()(T* p) const noexcept { Free(p); }
};
using ChipPtr = std::unique_ptr<gpiod_chip, Deleter<gpiod_chip, gpiod_chip_close>>;
using ChipInfoPtr =
    std::unique_ptr<gpiod_chip_info, Deleter<gpiod_chip_info, gpiod_chip_info_free>>;
using SettingsPtr =
    std::unique_ptr<gpiod_line_settings, Deleter<gpiod_line_settings, gpiod_line_settings_free>>;
using LineConfigPtr =
    std::unique_ptr<gpiod_line_config, Deleter<gpiod_line_config, gpiod_line_config_free>>;
using RequestConfigPtr =
    std::unique_ptr<gpiod_request_config, Deleter<gpiod_request_config, gpiod_request_config_free>>;
using RequestPtr =
    std::unique_ptr<gpiod_line_request, Deleter<gpiod_line_request, gpiod_line_request_release>>;
using EventBufferPtr =
    std::unique_ptr<gpiod_edge_event_buffer,
                    Deleter<gpiod_edge_event_buffer, gpiod_edge_event_buffer_free>>;

std::string errno_text() {
    return std::strerror(errno);
}

bool all_digits(std::string_view s) {
    return !s.empty() &&
           std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// 2.x opens chips by path only; the board file may name one as 1.x's
// gpiod_chip_open_lookup took it: a path, "gpiochip0", "0" or the chip's
// label. nullptr with errno set when none matches.
ChipPtr open_chip(const std::string& chip) {
    if (chip.find('/') != std::string::npos)
        return ChipPtr(gpiod_chip_open(chip.c_str()));
    const std::string by_name = "/dev/" + (all_digits(chip) ? "gpiochip" + chip : chip);
    struct stat st {};
    if (stat(by_name.c_str(), &st) == 0)
        return ChipPtr(gpiod_chip_open(by_name.c_str()));
    // A label: ask each chip (a board has a handful).
    std::error_code ec;
    for (std::filesystem::directory_iterator it("/dev", ec), end; !ec && it != end;
         it.increment(ec)) {
        const std::string path = it->path().string();
        if (it->path().filename().string().rfind("gpiochip", 0) != 0 ||
            !gpiod_is_gpiochip_device(path.c_str()))
            continue;
        ChipPtr candidate(gpiod_chip_open(path.c_str()));
        if (!candidate)
            continue;
        const ChipInfoPtr info(gpiod_chip_get_info(candidate.get()));
        if (info && chip == gpiod_chip_info_get_label(info.get()))
            return candidate;
    }
    errno = ENOENT;
    return nullptr;
}

class LineV2 final : public Line {
public:
    LineV2(const ChipPtr& chip, std::string label, const GpioLineConfig& config,
           const std::string& device, const std::string& consumer, bool output, bool initial_active)
        : Line(device, std::move(label)), offset_(config.offset) {
        const SettingsPtr settings(gpiod_line_settings_new());
        const LineConfigPtr line_config(gpiod_line_config_new());
        const RequestConfigPtr request_config(gpiod_request_config_new());
        if (!settings || !line_config || !request_config)
            throw std::bad_alloc();
        gpiod_line_settings_set_active_low(settings.get(), config.active_low);
        int set = 0;
        if (output) {
            set |= gpiod_line_settings_set_direction(settings.get(), GPIOD_LINE_DIRECTION_OUTPUT);
            set |= gpiod_line_settings_set_output_value(settings.get(),
                                                        initial_active ? GPIOD_LINE_VALUE_ACTIVE
                                                                       : GPIOD_LINE_VALUE_INACTIVE);
        } else {
            set |= gpiod_line_settings_set_direction(settings.get(), GPIOD_LINE_DIRECTION_INPUT);
            set |= gpiod_line_settings_set_edge_detection(settings.get(), GPIOD_LINE_EDGE_BOTH);
            // The debouncer compares event times with each other only; the
            // monotonic clock is 2.x's default, said here so that it stays.
            set |= gpiod_line_settings_set_event_clock(settings.get(), GPIOD_LINE_CLOCK_MONOTONIC);
        }
        const unsigned int offset = config.offset;
        if (set != 0 ||
            gpiod_line_config_add_line_settings(line_config.get(), &offset, 1, settings.get()) != 0)
            throw DeviceError(DeviceKind::gpio, name(),
                              "cannot configure the request: " + errno_text());
        gpiod_request_config_set_consumer(request_config.get(), consumer.c_str());
        request_.reset(
            gpiod_chip_request_lines(chip.get(), request_config.get(), line_config.get()));
        if (!request_)
            throw DeviceError(DeviceKind::gpio, name(),
                              "cannot request the line (held by another process?): " +
                                  errno_text());
        if (!output) {
            events_.reset(gpiod_edge_event_buffer_new(kEventBuffer));
            if (!events_)
                throw std::bad_alloc();
        }
    }

    void set(bool active) override {
        if (gpiod_line_request_set_value(request_.get(), offset_,
                                         active ? GPIOD_LINE_VALUE_ACTIVE
                                                : GPIOD_LINE_VALUE_INACTIVE) != 0)
            throw DeviceError(DeviceKind::gpio, name(), "cannot set the line: " + errno_text());
    }

    std::optional<Edge> wait_edge(std::chrono::nanoseconds timeout) override {
        // 2.x reads events in batches; the rest of a batch is handed out
        // before the kernel is asked again, so that none is lost.
        if (next_ >= read_) {
            const int ready = gpiod_line_request_wait_edge_events(
                request_.get(), std::max<std::int64_t>(0, timeout.count()));
            // A signal (SIGTERM from systemd) ends the wait like a timeout:
            // the caller looks at its stop flag.
            if (ready < 0 && errno == EINTR)
                return std::nullopt;
            if (ready < 0)
                throw DeviceError(DeviceKind::gpio, name(),
                                  "waiting for an edge failed: " + errno_text());
            if (ready == 0)
                return std::nullopt;
            const int read =
                gpiod_line_request_read_edge_events(request_.get(), events_.get(), kEventBuffer);
            if (read <= 0)
                throw DeviceError(DeviceKind::gpio, name(),
                                  "reading an edge failed: " + errno_text());
            read_ = static_cast<std::size_t>(read);
            next_ = 0;
        }
        gpiod_edge_event* event = gpiod_edge_event_buffer_get_event(events_.get(), next_++);
        Edge edge;
        edge.timestamp_ns = static_cast<std::int64_t>(gpiod_edge_event_get_timestamp_ns(event));
        edge.rising = gpiod_edge_event_get_event_type(event) == GPIOD_EDGE_EVENT_RISING_EDGE;
        return edge;
    }

private:
    static constexpr std::size_t kEventBuffer = 16; // the kernel's own queue for one line
    unsigned int offset_;
    RequestPtr request_;
    EventBufferPtr events_; // edge lines only
    std::size_t read_ = 0;  // events in the buffer
    std::size_t next_ = 0;  // the next one to hand out
};

// The chip where `config`'s line is, and its label. The kernel would refuse
// an offset past the end with EINVAL too, but as a failed request; 1.x tells
// it apart, and so does this.
std::unique_ptr<Line> open_line(const GpioLineConfig& config, const std::string& chip,
                                const std::string& name, const std::string& consumer, bool output,
                                bool initial_active) {
    const ChipPtr opened = open_chip(chip);
    if (!opened)
        throw DeviceError(DeviceKind::gpio, name, "cannot open the chip: " + errno_text());
    const ChipInfoPtr info(gpiod_chip_get_info(opened.get()));
    if (!info)
        throw DeviceError(DeviceKind::gpio, name, "cannot open the chip: " + errno_text());
    if (config.offset >= gpiod_chip_info_get_num_lines(info.get()))
        throw DeviceError(DeviceKind::gpio, name,
                          "no such line on the chip: " + std::string(std::strerror(EINVAL)));
    const char* label = gpiod_chip_info_get_label(info.get());
    return std::make_unique<LineV2>(opened, label ? label : "", config, name, consumer, output,
                                    initial_active);
}

} // namespace

std::unique_ptr<Line> open_output_line(const GpioLineConfig& config, const std::string& chip,
                                       const std::string& name, const std::string& consumer,
                                       bool initial_active) {
    return open_line(config, chip, name, consumer, true, initial_active);
}

std::unique_ptr<Line> open_edge_line(const GpioLineConfig& config, const std::string& chip,
                                     const std::string& name, const std::string& consumer) {
    return open_line(config, chip, name, consumer, false, false);
}

} // namespace fpp::drivers::gpio_detail
