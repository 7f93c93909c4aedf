#pragma once
// The virtual scanner wired up as a board (a board file with a sim section):
// rig, scene and renderer, the sim display, camera, trigger line (wired to the
// camera's trigger input), button and LED, on a virtual or steady clock. With
// camera.driver aravis the sim camera is the sensor of a GigE Vision link:
// its frames reach the scanner through Aravis's fake camera and the Aravis
// driver.
#include <memory>

#include <fpp/scanner/board_config.hpp>
#include <fpp/scanner/scanner.hpp>
#include <fpp/sim/renderer.hpp>
#include <fpp/sim/sim_camera.hpp>
#include <fpp/sim/sim_display.hpp>
#include <fpp/sim/sim_gpio.hpp>

namespace fpp::scanner {

class SimBoard {
public:
    // Throws InputError for a bad rig or scene file, DeviceError when the
    // GigE link cannot be set up, std::logic_error when
    // the board is not a sim board.
    explicit SimBoard(const BoardConfig& board);
    SimBoard(const SimBoard&) = delete;
    SimBoard& operator=(const SimBoard&) = delete;

    Devices devices();

    drivers::Clock& clock() { return *clock_; }
    const sim::Rig& rig() const { return rig_; }
    const sim::Renderer& renderer() const { return *renderer_; }
    sim::SimDisplay& display() { return *display_; }
    // The simulated sensor (behind the GigE link when there is one).
    sim::SimCamera& camera() { return *camera_; }
    sim::SimTrigger& trigger() { return *trigger_; }
    sim::SimButton& button() { return *button_; }
    sim::SimLed& led() { return *led_; }

private:
    std::unique_ptr<drivers::Clock> clock_;
    sim::Rig rig_;
    std::unique_ptr<sim::Renderer> renderer_;
    std::unique_ptr<sim::SimDisplay> display_;
    std::unique_ptr<sim::SimCamera> camera_;
    std::unique_ptr<drivers::Camera> gige_camera_; // camera.driver aravis
    std::unique_ptr<sim::SimTrigger> trigger_;
    std::unique_ptr<sim::SimButton> button_;
    std::unique_ptr<sim::SimLed> led_;
};

} // namespace fpp::scanner
