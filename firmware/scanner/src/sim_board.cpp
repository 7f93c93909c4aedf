#include "fpp/scanner/sim_board.hpp"

#include "sim_gige_camera.hpp"

#include "fpp/error.hpp"
#include "fpp/sim/rig.hpp"
#include "fpp/sim/scene.hpp"
#include "fpp/sim/sim_clock.hpp"

#include <stdexcept>

namespace fpp::scanner {

SimBoard::SimBoard(const BoardConfig& board) {
    if (!board.sim) throw std::logic_error("SimBoard on a board without a sim section");
    const SimConfig& s = *board.sim;
    if (s.virtual_clock) clock_ = std::make_unique<sim::VirtualClock>();
    else clock_ = std::make_unique<drivers::SteadyClock>();
    rig_ = sim::load_rig(s.rig);
    if (s.binning > 1) rig_ = rig_.binned_camera(s.binning);
    sim::Scene scene;
    try {
        scene = sim::scene_from_argument(s.scene);
    } catch (const std::invalid_argument& e) {
        throw InputError(board.file, "sim.scene", e.what());
    }
    renderer_ = std::make_unique<sim::Renderer>(rig_, scene);
    display_ = std::make_unique<sim::SimDisplay>(rig_.projector_size, *clock_, s.flip_latency);
    if (board.camera.driver == CameraDriver::aravis) {
        // The sensor is triggered by the link, from software.
        drivers::CameraSettings sensor = board.camera.settings;
        sensor.trigger = drivers::TriggerMode::software;
        camera_ = std::make_unique<sim::SimCamera>(*renderer_, *display_, *clock_, sensor, s.seed);
        gige_camera_ = make_sim_gige_camera(*camera_, board.camera.device, board.camera.settings);
    } else {
        camera_ = std::make_unique<sim::SimCamera>(*renderer_, *display_, *clock_,
                                                   board.camera.settings, s.seed);
    }
    trigger_ = std::make_unique<sim::SimTrigger>(
        *clock_, [camera = camera_.get()](std::int64_t t) { camera->line_trigger(t); });
    button_ = std::make_unique<sim::SimButton>(board.gpio.debounce);
    led_ = std::make_unique<sim::SimLed>();
}

Devices SimBoard::devices() {
    drivers::Camera& camera = gige_camera_ ? *gige_camera_ : static_cast<drivers::Camera&>(*camera_);
    return Devices{*display_, *trigger_, *button_, *led_, camera, *clock_};
}

} // namespace fpp::scanner
