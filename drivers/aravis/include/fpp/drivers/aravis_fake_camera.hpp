#pragma once
// Aravis's GigE Vision fake camera, run in this process, serving images that
// the caller supplies. For tests and for running the scanner without a real
// camera: the camera driver reaches it over UDP exactly as a real GigE camera.
//
// Facts that shape its use:
// - open it with AravisCamera by the address it listens on ("127.0.0.1"):
//   discovery broadcasts on other interfaces and the frames would not arrive;
// - it implements the software trigger but no line trigger;
// - one fake camera per network namespace (it binds the GVCP port 3956):
//   enter_private_network_namespace() lets test processes run in parallel.
#include <cstdint>
#include <memory>
#include <string>

#include <fpp/image.hpp>

namespace fpp::drivers {

class AravisFakeCamera {
public:
    // Starts the camera on `address` (an IPv4 address of a local interface)
    // with the image region `size` (at most 2048 x 2048). Throws DeviceError
    // if it cannot start (port taken, address not local).
    explicit AravisFakeCamera(Size size, const std::string& address = "127.0.0.1",
                              const std::string& serial = "FPP0");
    ~AravisFakeCamera();
    AravisFakeCamera(const AravisFakeCamera&) = delete;
    AravisFakeCamera& operator=(const AravisFakeCamera&) = delete;

    // The image sent with every following frame, converted to the pixel
    // format the camera is set to (Mono8: 16-bit frames keep their high byte;
    // Mono16: 8-bit frames are MSB-aligned). Must be of size `size`; throws
    // std::invalid_argument otherwise. Thread-safe.
    void set_image(const Frame& frame);

    // How often the camera looks for a software trigger (Hz, default 1000):
    // the latency from trigger to exposure is up to one period.
    void set_trigger_poll_rate(double hz);

    // Frames filled so far (each one sent, whole, to the stream).
    std::uint64_t frames_sent() const;

    const std::string& address() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Moves this process into a network namespace of its own with the loopback
// interface up, so that its fake camera's ports do not clash with other
// processes'. Must be called while the process has a single thread (before
// any GLib or worker thread starts). Returns false where that is not
// permitted (no CAP_SYS_ADMIN: nothing changed) or the loopback interface
// cannot be brought up.
bool enter_private_network_namespace();

} // namespace fpp::drivers
