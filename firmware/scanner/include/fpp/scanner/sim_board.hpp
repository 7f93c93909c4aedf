#pragma once
// The virtual scanner wired up as a board (a board file with a sim section):
// rig, scene and renderer, the sim display, camera, trigger line (wired to the
// camera's trigger input), button and LED, on a virtual or steady clock. With
// camera.driver aravis the sim camera is the sensor of a GigE Vision link:
// its frames reach the scanner through Aravis's fake camera and the Aravis
// driver.
//
// sim.scene "session:checkerboard:N" or "session:plane:N" holds a calibration
// board (fpp/simulator/session.hpp) at the N poses of a simulated session, moved on
// to the next pose at every scan, as a person would between button presses;
// the board's description is written to the store as board.yaml (unless one
// is there), so that capture-mode scans make a session folder for fpp-calib.
//
// With sim.camera_only the display, trigger, button and LED are the board's
// hardware (HardwareBoard) and only the camera and scene are simulated; the
// sim-side accessors below (display, trigger, button, led) are then not
// available.
#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include <fpp/scanner/board_config.hpp>
#include <fpp/scanner/hardware_board.hpp>
#include <fpp/scanner/scanner.hpp>
#include <fpp/sim/observed_display.hpp>
#include <fpp/sim/sim_camera.hpp>
#include <fpp/sim/sim_display.hpp>
#include <fpp/sim/sim_gpio.hpp>
#include <fpp/simulator/renderer.hpp>
#include <fpp/simulator/session.hpp>

namespace fpp::scanner {

class SimGigeCamera;

class SimBoard {
public:
    // Throws InputError for a bad rig or scene file, DeviceError when the
    // GigE link cannot be set up, std::logic_error when
    // the board is not a sim board. `log` takes the GigE camera's losses and
    // returns.
    explicit SimBoard(const BoardConfig& board, const Logger& log = Logger());
    ~SimBoard();
    SimBoard(const SimBoard&) = delete;
    SimBoard& operator=(const SimBoard&) = delete;

    Devices devices();

    // The calibration board's board.yaml of a session scene ("" otherwise).
    std::string session_board_yaml() const;

    drivers::Clock& clock() { return *clock_; }
    const sim::Rig& rig() const { return rig_; }
    const sim::Renderer& renderer() const { return *renderer_; }
    sim::SimDisplay& display() { return *display_; }
    // The simulated sensor (behind the GigE link when there is one).
    sim::SimCamera& camera() { return *camera_; }
    sim::SimTrigger& trigger() { return *trigger_; }
    sim::SimButton& button() { return *button_; }
    sim::SimLed& led() { return *led_; }

    // The simulated devices keep only their newest `limit` records of each
    // kind (exposures, flips, pulses, LED states), as the scanner daemon asks
    // (kDaemonRecordLimit): a virtual scanner that runs for months keeps
    // flat memory. Tests that check every record do not call it.
    void limit_records(std::size_t limit);
    static constexpr std::size_t kDaemonRecordLimit = 1024;

    // camera.driver aravis: the link's cable pulled (Aravis's fake camera
    // gone) and plugged back (a new one at the same address). The scanner
    // sees a camera that stops answering, then answers again.
    // std::logic_error without a GigE link.
    void unplug_camera();
    void plug_camera();

private:
    std::unique_ptr<drivers::Clock> clock_;
    sim::Rig rig_;
    std::unique_ptr<sim::Renderer> renderer_;
    std::unique_ptr<sim::SimDisplay> display_;
    std::unique_ptr<sim::SimCamera> camera_;
    // sim.camera_only: the hardware display and lines, the display observed.
    std::unique_ptr<HardwareBoard> hardware_;
    std::unique_ptr<sim::ObservedDisplay> observed_;
    std::unique_ptr<SimGigeCamera> gige_camera_; // camera.driver aravis
    std::unique_ptr<sim::SimTrigger> trigger_;
    std::unique_ptr<sim::SimButton> button_;
    std::unique_ptr<sim::SimLed> led_;
    // Session scenes.
    void next_session_pose();
    std::optional<sim::SessionOptions> session_;
    std::vector<sim::Pose> session_poses_;
    std::size_t pose_index_ = 0;
    std::size_t exposures_at_pose_ = 0;
};

} // namespace fpp::scanner
