#include "reopening_line.hpp"

#include <fpp/drivers/device_error.hpp>

#include <utility>

namespace fpp::drivers::gpio_detail {

ReopeningLine::ReopeningLine(const GpioLineConfig& config, std::string consumer, bool output,
                             bool initial_active)
    : config_(config), consumer_(std::move(consumer)), output_(output), name_(line_name(config)),
      lookup_(config.chip), line_(open(initial_active)) {
    // By label from now on: the number may be another chip's once this one
    // comes back. A chip without a label is looked for as the board file
    // says.
    if (!line_->chip_label().empty())
        lookup_ = line_->chip_label();
}

std::unique_ptr<Line> ReopeningLine::open(bool initial_active) const {
    return output_ ? open_output_line(config_, lookup_, name_, consumer_, initial_active)
                   : open_edge_line(config_, lookup_, name_, consumer_);
}

void ReopeningLine::set(bool active) {
    if (line_) {
        try {
            line_->set(active);
            return;
        } catch (const DeviceError&) {
            line_.reset(); // the kernel's request of a chip that went away
        }
    }
    line_ = open(active); // requested at the level asked for: nothing left to set
}

std::optional<Edge> ReopeningLine::wait_edge(std::chrono::nanoseconds timeout) {
    if (!line_)
        line_ = open(false);
    try {
        return line_->wait_edge(timeout);
    } catch (const DeviceError&) {
        line_.reset();
        throw;
    }
}

} // namespace fpp::drivers::gpio_detail
