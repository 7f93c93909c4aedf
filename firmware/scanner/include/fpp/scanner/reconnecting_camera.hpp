#pragma once
// A camera that comes back after it was lost (a GigE cable pulled, a camera
// power-cycled): the scanner keeps running and the next scan after the
// camera answers again succeeds, with no restart of the service.
//
// A DeviceError from the camera ends the scan attempt as before (the scanner
// retries once, then fails with the reason and the LED in error); the camera
// it came from is closed, since a driver whose device went away does not
// recover its control and stream channels. The next call that needs the
// camera opens it again through the opener and puts back the exposure set
// through this object. Opening fails with the opener's DeviceError while the
// camera is still away; nothing waits or retries here: the scan's own retry
// and the next scan are the attempts.
//
// Threading: as drivers::Camera, one thread owns it.
#include <memory>
#include <optional>
#include <string>

#include <fpp/drivers/camera.hpp>
#include <fpp/scanner/camera_wait.hpp>
#include <fpp/scanner/log.hpp>

namespace fpp::scanner {

class ReconnectingCamera final : public drivers::Camera {
public:
    // `first`: the camera as opened by `open` (non-null); its size, depth and
    // exposure range are the ones every reopened camera must have (a camera
    // that comes back at another size or depth is refused with DeviceError:
    // the table and the decoder are for this one). `name` names the camera
    // in log lines ("camera 192.168.1.20").
    ReconnectingCamera(CameraOpener open, std::unique_ptr<drivers::Camera> first, std::string name,
                       Logger log);

    Size size() const override { return size_; }
    int bit_depth() const override { return bit_depth_; }
    drivers::ExposureRange exposure_range_us() const override { return range_; }

    void start() override;
    void stop() override;
    void set_exposure_us(double exposure_us) override;
    void software_trigger() override;
    drivers::CapturedFrame next_frame(std::chrono::milliseconds timeout) override;
    // 0 while the camera is closed (a closed camera holds no frame).
    std::size_t frames_waiting() const override;

    // False between a loss and the next successful open.
    bool connected() const { return camera_ != nullptr; }
    // Times the camera was lost, and opened again, since construction.
    int losses() const { return losses_; }
    int reconnections() const { return reconnections_; }

private:
    // The open camera, opened again first when it was lost.
    drivers::Camera& live();
    // After a DeviceError from the camera: close it (stop() first, errors
    // ignored: the device is already failing).
    void lose(const std::string& why);
    template <class Call> decltype(auto) guarded(Call call);

    CameraOpener open_;
    std::unique_ptr<drivers::Camera> camera_;
    std::string name_;
    Logger log_;
    Size size_;
    int bit_depth_;
    drivers::ExposureRange range_;
    std::optional<double> exposure_us_; // set through this object: put back on reopen
    int losses_ = 0;
    int reconnections_ = 0;
};

} // namespace fpp::scanner
