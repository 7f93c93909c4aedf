#include "fpp/sim/sim_camera.hpp"

#include "fpp/drivers/device_error.hpp"
#include "fpp/error.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>

namespace fpp::sim {

namespace {
const char* const kDevice = "sim camera";

// Microseconds as people write them: "10", "1000000", "2.5".
std::string format_us(double us) {
    char text[32];
    std::snprintf(text, sizeof text, "%.10g", us);
    return text;
}
} // namespace

SimCamera::SimCamera(const Renderer& renderer, const Screen& display, drivers::Clock& clock,
                     const drivers::CameraSettings& settings, std::uint64_t noise_seed)
    : renderer_(&renderer), display_(display), clock_(clock), settings_(settings),
      nominal_exposure_us_(settings.exposure_us), seed_(noise_seed),
      dark_(renderer.rig().projector_size) {}

Size SimCamera::size() const {
    return renderer_->rig().camera_size;
}

int SimCamera::bit_depth() const {
    return renderer_->rig().sensor.bit_depth > 8 ? 16 : 8;
}

void SimCamera::check_present() const {
    if (gone_)
        throw drivers::DeviceError(drivers::DeviceKind::camera, kDevice,
                                   "camera gone (no response)");
}

void SimCamera::start() {
    check_present();
    if (on_start_)
        on_start_();
    streaming_ = true;
}

void SimCamera::on_start(std::function<void()> hook) {
    on_start_ = std::move(hook);
}

void SimCamera::set_renderer(const Renderer& renderer) {
    if (!(renderer.rig().camera_size == renderer_->rig().camera_size))
        throw std::invalid_argument("SimCamera::set_renderer: another camera size");
    renderer_ = &renderer;
}

void SimCamera::stop() {
    streaming_ = false;
    queue_.clear(); // buffers go back to the pool
}

void SimCamera::inject_fault(CameraFault fault, int at_trigger) {
    fault_ = fault;
    fault_at_ = at_trigger;
}

void SimCamera::set_exposure_range_us(drivers::ExposureRange range) {
    if (!(range.min_us > 0) || !(range.min_us <= range.max_us) || !std::isfinite(range.max_us))
        throw std::invalid_argument("SimCamera::set_exposure_range_us: need 0 < min_us <= max_us");
    exposure_range_ = range;
}

void SimCamera::set_exposure_us(double exposure_us) {
    check_present();
    if (!exposure_range_.contains(exposure_us))
        throw InputError("sim camera settings", "exposure_us",
                         format_us(exposure_us) + " us is outside the camera's exposure range " +
                             format_us(exposure_range_.min_us) + ".." +
                             format_us(exposure_range_.max_us) + " us");
    if (streaming_)
        throw drivers::DeviceError(drivers::DeviceKind::camera, kDevice,
                                   "exposure changed while streaming");
    settings_.exposure_us = exposure_us;
}

void SimCamera::software_trigger() {
    check_present();
    if (settings_.trigger != drivers::TriggerMode::software)
        throw drivers::DeviceError(drivers::DeviceKind::camera, kDevice,
                                   "software trigger while triggered by line " +
                                       settings_.trigger_source);
    if (!streaming_)
        throw drivers::DeviceError(drivers::DeviceKind::camera, kDevice,
                                   "software trigger while stopped");
    expose(clock_.now_ns());
}

void SimCamera::line_trigger(std::int64_t t_ns) {
    if (gone_ || !streaming_ || settings_.trigger != drivers::TriggerMode::line)
        return;
    expose(t_ns);
}

void SimCamera::set_next_frame_id(std::uint64_t next, bool wrap_16_bit) {
    if (next == 0 || (wrap_16_bit && next > 0xFFFFu))
        throw std::invalid_argument("SimCamera::set_next_frame_id: " + std::to_string(next) +
                                    " is not a frame id");
    next_frame_id_ = next;
    wrap_16_bit_ = wrap_16_bit;
}

void SimCamera::expose(std::int64_t t_ns) {
    const int trigger = triggers_++;
    CameraFault fault = trigger == fault_at_ ? fault_ : CameraFault::none;
    if (fault == CameraFault::gone) {
        gone_ = true;
        return;
    }
    const auto advance = [this] {
        const std::uint64_t id = next_frame_id_++;
        if (wrap_16_bit_ && next_frame_id_ > 0xFFFFu)
            next_frame_id_ = 1;
        return id;
    };
    if (fault == CameraFault::dropped)
        advance();
    Exposure e;
    e.frame_id = advance();
    e.start_ns = t_ns;
    e.pattern = display_.on_screen_at(t_ns);
    const auto exposure_ns = static_cast<std::int64_t>(settings_.exposure_us * 1000.0);
    e.pattern_at_end = display_.on_screen_at(t_ns + exposure_ns);
    exposures_.push(e);
    if (fault == CameraFault::timeout)
        return;
    queue_.push_back({e, fault == CameraFault::incomplete});
    if (fault == CameraFault::doubled) {
        // The repeated trigger exposes again as soon as the sensor is free.
        Exposure again = e;
        again.frame_id = advance();
        again.start_ns = t_ns + exposure_ns;
        again.pattern = e.pattern_at_end;
        again.pattern_at_end = display_.on_screen_at(again.start_ns + exposure_ns);
        exposures_.push(again);
        queue_.push_back({again, false});
    }
}

drivers::CapturedFrame SimCamera::next_frame(std::chrono::milliseconds timeout) {
    check_present();
    if (queue_.empty()) {
        clock_.sleep_for(timeout);
        throw drivers::DeviceError(drivers::DeviceKind::camera, kDevice,
                                   "no frame within " + std::to_string(timeout.count()) + " ms");
    }
    Pending p = queue_.front();
    queue_.pop_front();
    // The frame is complete once the exposure ends.
    clock_.sleep_until_ns(p.exposure.start_ns +
                          static_cast<std::int64_t>(settings_.exposure_us * 1000.0));
    if (p.incomplete)
        throw drivers::DeviceError(drivers::DeviceKind::camera, kDevice,
                                   "frame " + std::to_string(p.exposure.frame_id) +
                                       " incomplete (missing packets)");
    const Image<std::uint8_t>& light =
        p.exposure.pattern == Screen::kNothing
            ? dark_
            : display_.pattern(static_cast<std::size_t>(p.exposure.pattern));
    drivers::CapturedFrame out;
    out.frame =
        renderer_->render(light, Renderer::frame_seed(seed_, static_cast<int>(p.exposure.frame_id)),
                          settings_.exposure_us / nominal_exposure_us_);
    out.frame_id = p.exposure.frame_id;
    out.timestamp_ns = p.exposure.start_ns;
    return out;
}

} // namespace fpp::sim
