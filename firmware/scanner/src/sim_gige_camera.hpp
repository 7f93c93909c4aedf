#pragma once
// The virtual scanner's camera behind a real GigE Vision link: each software
// trigger exposes the simulated sensor (the scene under the pattern on screen
// at that instant), hands the image to Aravis's fake GigE camera on a local
// address, and triggers it through the Aravis driver, which receives the
// frame over UDP as from a real camera. Only the sensor is simulated; the
// stream, its buffers, frame ids and timeouts are Aravis's.
#include <chrono>
#include <memory>
#include <string>

#include <fpp/drivers/camera.hpp>
#include <fpp/scanner/log.hpp>
#include <fpp/sim/sim_camera.hpp>

namespace fpp::scanner {

// The driver's end is a ReconnectingCamera, as on a hardware board: the
// link's cable can be pulled and plugged back (the fault tests), and the
// scanner recovers as it does from a real camera's loss.
class SimGigeCamera : public drivers::Camera {
public:
    // The cable pulled: the fake camera is gone (its ports closed), so the
    // driver's requests and the stream go unanswered.
    virtual void unplug() = 0;
    // Plugged back: a fake camera answers at the same address again (a new
    // one, as after a power cycle). Throws DeviceError if it cannot start.
    virtual void plug() = 0;
};

// Builds the link, or throws DeviceError when the fake camera cannot start
// (address not local, port taken) or the driver cannot reach it, and
// InputError for settings the driver refuses. `sensor` must outlive the
// camera and use software triggering. `log` takes the camera's losses and
// returns.
std::unique_ptr<SimGigeCamera> make_sim_gige_camera(sim::SimCamera& sensor,
                                                    const std::string& address,
                                                    const drivers::CameraSettings& settings,
                                                    const Logger& log);

} // namespace fpp::scanner
