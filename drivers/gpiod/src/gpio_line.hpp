#pragma once
// One requested GPIO line, independent of the libgpiod version. Each libgpiod
// major version implements open_output_line / open_edge_line in a file of its
// own (gpio_line_v1.cpp for 1.x, gpio_line_v2.cpp for 2.x); CMakeLists.txt
// builds the one of the libgpiod it finds.
#include <fpp/drivers/gpiod_lines.hpp>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

namespace fpp::drivers::gpio_detail {

struct Edge {
    std::int64_t timestamp_ns = 0; // kernel event time
    bool rising = false;           // logical (after active-low)
};

class Line {
public:
    virtual ~Line() = default;
    // Logical level of an output line.
    virtual void set(bool active) = 0;
    // Waits up to `timeout` for an edge of an input line; nullopt on timeout.
    virtual std::optional<Edge> wait_edge(std::chrono::nanoseconds timeout) = 0;
    const std::string& name() const { return name_; }
    // The chip's label ("9030000.pl061", "pinctrl-rp1"): how it is found
    // again when it comes back under another number. Empty if it has none.
    const std::string& chip_label() const { return chip_label_; }

protected:
    Line(std::string name, std::string chip_label)
        : name_(std::move(name)), chip_label_(std::move(chip_label)) {}

private:
    std::string name_;
    std::string chip_label_;
};

// "gpiochip0 line 17 (board.yaml gpio.led_line)": the device name in
// DeviceError messages.
inline std::string line_name(const GpioLineConfig& config) {
    return config.chip + " line " + std::to_string(config.offset) +
           (config.field.empty() ? "" : " (" + config.field + ")");
}

// Throw DeviceError(name, ...) when the chip or line cannot be had. `chip`
// is where to look (config.chip, or a label when opened again); `name` is
// the one messages use (line_name(config) from the board file).
std::unique_ptr<Line> open_output_line(const GpioLineConfig& config, const std::string& chip,
                                       const std::string& name, const std::string& consumer,
                                       bool initial_active);
std::unique_ptr<Line> open_edge_line(const GpioLineConfig& config, const std::string& chip,
                                     const std::string& name, const std::string& consumer);

} // namespace fpp::drivers::gpio_detail
