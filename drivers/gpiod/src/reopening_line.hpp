#pragma once
// A line that is requested again after its chip went away and came back
// (gpiod_lines.hpp says what a user sees). Wraps the version-specific Line
// of gpio_line.hpp; the three roles hold one each.
#include "gpio_line.hpp"

#include <memory>
#include <optional>
#include <string>

namespace fpp::drivers::gpio_detail {

class ReopeningLine {
public:
    // Requests the line now (DeviceError when it cannot be had: a board
    // file's mistake is reported at start, not at first use).
    ReopeningLine(const GpioLineConfig& config, std::string consumer, bool output,
                  bool initial_active);

    // An output's logical level. A request whose chip went away is released
    // and made again at once (the chip may be back: the trigger's first
    // pulse after a return must go out); DeviceError when that fails too.
    void set(bool active);
    // An input's next edge (nullopt on timeout). A failure releases the
    // request and throws; the next call requests the line again first.
    std::optional<Edge> wait_edge(std::chrono::nanoseconds timeout);

    // False between a failure and the next successful request.
    bool held() const { return line_ != nullptr; }
    const std::string& name() const { return name_; }

private:
    std::unique_ptr<Line> open(bool initial_active) const;

    GpioLineConfig config_;
    std::string consumer_;
    bool output_;
    std::string name_;   // line_name(config_): the board file's words
    std::string lookup_; // where the chip is looked for: its label once known
    std::unique_ptr<Line> line_;
};

} // namespace fpp::drivers::gpio_detail
