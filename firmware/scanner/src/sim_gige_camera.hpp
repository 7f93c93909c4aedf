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
#include <fpp/sim/sim_camera.hpp>

namespace fpp::scanner {

// Builds the link, or throws DeviceError when the fake camera cannot start
// (address not local, port taken) or the driver cannot reach it, and
// InputError for settings the driver refuses. `sensor` must outlive the
// camera and use software triggering.
std::unique_ptr<drivers::Camera> make_sim_gige_camera(sim::SimCamera& sensor,
                                                      const std::string& address,
                                                      const drivers::CameraSettings& settings);

} // namespace fpp::scanner
