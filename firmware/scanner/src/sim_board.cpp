#include "fpp/scanner/sim_board.hpp"

#include "sim_gige_camera.hpp"

#include "fpp/scanner/hardware_board.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/enum_names.hpp"
#include "fpp/error.hpp"
#include "fpp/sim/sim_clock.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <charconv>
#include <filesystem>
#include <stdexcept>
#include <string_view>

namespace fpp::scanner {

namespace {

constexpr std::string_view kSessionPrefix = "session:";

// "session:checkerboard:N" or "session:plane:N": the calibration board of a
// simulated session (fpp/simulator/session.hpp) at its N poses.
sim::SessionOptions parse_session_scene(const std::string& text) {
    const std::string rest = text.substr(kSessionPrefix.size());
    const auto colon = rest.find(':');
    const std::string kind = rest.substr(0, colon);
    sim::SessionOptions o;
    if (const auto k = value_of(sim::kSessionKindNames, kind))
        o.kind = *k;
    else
        throw std::invalid_argument("session scene '" + text + "': the board must be " +
                                    names_list(sim::kSessionKindNames, " or "));
    int poses = 0;
    const std::string count = colon == std::string::npos ? "" : rest.substr(colon + 1);
    const auto [end, ec] = std::from_chars(count.data(), count.data() + count.size(), poses);
    if (ec != std::errc() || end != count.data() + count.size() || poses < 1 || poses > 200)
        throw std::invalid_argument("session scene '" + text +
                                    "': give 1..200 poses, e.g. session:" + kind + ":15");
    o.poses = poses;
    return o;
}

} // namespace

SimBoard::SimBoard(const BoardConfig& board, const Logger& log) {
    if (!board.sim)
        throw std::logic_error("SimBoard on a board without a sim section");
    const SimConfig& s = *board.sim;
    if (s.virtual_clock)
        clock_ = std::make_unique<sim::VirtualClock>();
    else
        clock_ = std::make_unique<drivers::SteadyClock>();
    rig_ = sim::load_rig(s.rig);
    if (s.binning > 1)
        rig_ = rig_.binned_camera(s.binning);
    sim::Scene scene;
    try {
        if (s.scene.starts_with(kSessionPrefix)) {
            session_ = parse_session_scene(s.scene);
            session_->seed = s.seed;
            session_poses_ = sim::session_poses(rig_, *session_);
            scene = sim::session_scene(*session_, session_poses_[0]);
        } else {
            scene = sim::scene_from_argument(s.scene);
        }
    } catch (const std::invalid_argument& e) {
        throw InputError(board.file, "sim.scene", e.what());
    }
    renderer_ = std::make_unique<sim::Renderer>(rig_, scene);
    const sim::Screen* screen = nullptr;
    if (s.camera_only) {
        // The board's own display and lines; the camera sees what the display
        // has really flipped to.
        hardware_ = std::make_unique<HardwareBoard>(board);
        if (!(hardware_->display().size() == rig_.projector_size))
            throw InputError(board.file, "sim.rig",
                             "the rig's projector is " + std::to_string(rig_.projector_size.width) +
                                 "x" + std::to_string(rig_.projector_size.height) +
                                 ", the display shows " +
                                 std::to_string(hardware_->display().size().width) + "x" +
                                 std::to_string(hardware_->display().size().height));
        observed_ = std::make_unique<sim::ObservedDisplay>(hardware_->display());
        screen = observed_.get();
    } else {
        display_ = std::make_unique<sim::SimDisplay>(rig_.projector_size, *clock_, s.flip_latency);
        screen = display_.get();
    }
    if (board.camera.driver == CameraDriver::aravis) {
        // The sensor is triggered by the link, from software.
        drivers::CameraSettings sensor = board.camera.settings;
        sensor.trigger = drivers::TriggerMode::software;
        camera_ = std::make_unique<sim::SimCamera>(*renderer_, *screen, *clock_, sensor, s.seed);
        gige_camera_ =
            make_sim_gige_camera(*camera_, board.camera.device, board.camera.settings, log);
    } else {
        camera_ = std::make_unique<sim::SimCamera>(*renderer_, *screen, *clock_,
                                                   board.camera.settings, s.seed);
    }
    if (session_) {
        // The board's description, as a person would write it for the board
        // they hold, so that the store is a session folder for fpp-calib.
        const auto board_yaml = board.store.directory / "board.yaml";
        if (!std::filesystem::exists(board_yaml)) {
            std::filesystem::create_directories(board.store.directory);
            write_file_atomically(board_yaml, sim::session_board_yaml(*session_));
        }
        camera_->on_start([this] { next_session_pose(); });
    }
    if (hardware_)
        return;
    trigger_ = std::make_unique<sim::SimTrigger>(
        *clock_, [camera = camera_.get()](std::int64_t t) { camera->line_trigger(t); });
    button_ = std::make_unique<sim::SimButton>(board.gpio.debounce);
    led_ = std::make_unique<sim::SimLed>();
}

SimBoard::~SimBoard() = default;

void SimBoard::unplug_camera() {
    if (!gige_camera_)
        throw std::logic_error("SimBoard::unplug_camera: the board has no GigE link");
    gige_camera_->unplug();
}

void SimBoard::plug_camera() {
    if (!gige_camera_)
        throw std::logic_error("SimBoard::plug_camera: the board has no GigE link");
    gige_camera_->plug();
}

void SimBoard::limit_records(std::size_t limit) {
    camera_->limit_records(limit);
    if (display_) // (an observed hardware display keeps only the current scan)
        display_->limit_records(limit);
    if (trigger_)
        trigger_->limit_records(limit);
    if (led_)
        led_->limit_records(limit);
}

void SimBoard::next_session_pose() {
    // A scan that took no frame (an attempt that failed at once) and a
    // preview (one frame) keep the pose; any other scan moves the board on,
    // cycling through the poses.
    if (camera_->exposures_taken() <= exposures_at_pose_ + 1) {
        exposures_at_pose_ = camera_->exposures_taken();
        return;
    }
    exposures_at_pose_ = camera_->exposures_taken();
    pose_index_ = (pose_index_ + 1) % session_poses_.size();
    auto next = std::make_unique<sim::Renderer>(
        rig_, sim::session_scene(*session_, session_poses_[pose_index_]));
    camera_->set_renderer(*next);
    renderer_ = std::move(next);
}

std::string SimBoard::session_board_yaml() const {
    return session_ ? sim::session_board_yaml(*session_) : std::string();
}

Devices SimBoard::devices() {
    drivers::Camera& camera =
        gige_camera_ ? *gige_camera_ : static_cast<drivers::Camera&>(*camera_);
    if (hardware_)
        return Devices{
            *observed_, hardware_->trigger(), hardware_->button(), hardware_->led(), camera,
            *clock_};
    return Devices{*display_, *trigger_, *button_, *led_, camera, *clock_};
}

} // namespace fpp::scanner
