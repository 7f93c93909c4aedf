#include "fpp/scanner/reconnecting_camera.hpp"

#include "fpp/drivers/device_error.hpp"

#include <stdexcept>
#include <utility>

namespace fpp::scanner {

ReconnectingCamera::ReconnectingCamera(CameraOpener open, std::unique_ptr<drivers::Camera> first,
                                       std::string name, Logger log)
    : open_(std::move(open)), camera_(std::move(first)), name_(std::move(name)),
      log_(std::move(log)) {
    if (!open_ || !camera_)
        throw std::invalid_argument("ReconnectingCamera: an opener and an open camera are needed");
    size_ = camera_->size();
    bit_depth_ = camera_->bit_depth();
    range_ = camera_->exposure_range_us();
}

template <class Call> decltype(auto) ReconnectingCamera::guarded(Call call) {
    drivers::Camera& camera = live();
    try {
        return call(camera);
    } catch (const drivers::DeviceError& e) {
        lose(e.what());
        throw;
    }
}

drivers::Camera& ReconnectingCamera::live() {
    if (camera_)
        return *camera_;
    std::unique_ptr<drivers::Camera> camera = open_(); // DeviceError while still away
    if (!(camera->size() == size_) || camera->bit_depth() != bit_depth_)
        throw drivers::DeviceError(
            drivers::DeviceKind::camera, name_,
            "came back as " + std::to_string(camera->size().width) + "x" +
                std::to_string(camera->size().height) + " " + std::to_string(camera->bit_depth()) +
                "-bit, was " + std::to_string(size_.width) + "x" + std::to_string(size_.height) +
                " " + std::to_string(bit_depth_) + "-bit: restart the scanner for another camera");
    if (exposure_us_)
        camera->set_exposure_us(*exposure_us_);
    range_ = camera->exposure_range_us();
    camera_ = std::move(camera);
    ++reconnections_;
    log_.info(name_ + " answers again (reconnection " + std::to_string(reconnections_) + ")");
    return *camera_;
}

void ReconnectingCamera::lose(const std::string& why) {
    if (!camera_)
        return;
    try {
        camera_->stop();
    } catch (const std::exception&) {
    }
    camera_.reset();
    ++losses_;
    log_.warning(name_ + " closed after an error (" + why + "); opened again when next needed");
}

void ReconnectingCamera::start() {
    guarded([](drivers::Camera& c) { c.start(); });
}

void ReconnectingCamera::stop() {
    if (camera_) // a lost camera is closed, so stopped
        guarded([](drivers::Camera& c) { c.stop(); });
}

void ReconnectingCamera::set_exposure_us(double exposure_us) {
    guarded([exposure_us](drivers::Camera& c) { c.set_exposure_us(exposure_us); });
    exposure_us_ = exposure_us;
}

void ReconnectingCamera::software_trigger() {
    guarded([](drivers::Camera& c) { c.software_trigger(); });
}

drivers::CapturedFrame ReconnectingCamera::next_frame(std::chrono::milliseconds timeout) {
    return guarded([timeout](drivers::Camera& c) { return c.next_frame(timeout); });
}

std::size_t ReconnectingCamera::frames_waiting() const {
    return camera_ ? camera_->frames_waiting() : 0;
}

} // namespace fpp::scanner
