#pragma once
// The camera of the virtual scanner behind fpp::drivers::Camera. At each
// trigger (software or the sim trigger line) it notes the pattern on screen
// at that instant (a SimDisplay, or a real display seen through
// ObservedDisplay) and renders the scene under it: a trigger fired before
// its flip completed captures the previous pattern,
// exactly the mistake a real rig would make. Fault hooks for tests.
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <vector>

#include <fpp/drivers/camera.hpp>
#include <fpp/drivers/clock.hpp>
#include <fpp/sim/record_log.hpp>
#include <fpp/sim/screen.hpp>
#include <fpp/simulator/renderer.hpp>

namespace fpp::sim {

enum class CameraFault {
    none,
    gone,       // the camera disappears: every later call throws
    timeout,    // the frame of this trigger never arrives
    dropped,    // a frame was lost inside the camera: this one arrives with its id one too far
    incomplete, // the frame arrives with missing packets
    doubled,    // the trigger fires twice (a software trigger repeated on a lossy link)
};

// What the sensor saw for one trigger.
struct Exposure {
    std::uint64_t frame_id = 0;
    std::int64_t start_ns = 0;
    int pattern = Screen::kNothing;        // on screen at exposure start
    int pattern_at_end = Screen::kNothing; // on screen at exposure end
};

class SimCamera final : public drivers::Camera {
public:
    // The renderer must outlive the camera. Settings: trigger mode, exposure
    // (time spent before the frame is read out; the rig's brightness is that
    // of this first exposure, and scales with later ones; not checked against
    // the range) and frame timeout are used.
    SimCamera(const Renderer& renderer, const Screen& screen, drivers::Clock& clock,
              const drivers::CameraSettings& settings, std::uint64_t noise_seed = 1);

    Size size() const override;
    int bit_depth() const override;
    void start() override;
    void stop() override;
    // kDefaultExposureRange unless set_exposure_range_us() changed it.
    drivers::ExposureRange exposure_range_us() const override { return exposure_range_; }
    // InputError("sim camera settings", "exposure_us", ...) naming the range
    // outside exposure_range_us(); DeviceError while streaming.
    void set_exposure_us(double exposure_us) override;
    void software_trigger() override;
    drivers::CapturedFrame next_frame(std::chrono::milliseconds timeout) override;
    std::size_t frames_waiting() const override { return queue_.size(); }

    // --- simulation side ---
    // The exposure times of a typical machine-vision sensor, microseconds.
    static constexpr drivers::ExposureRange kDefaultExposureRange{10.0, 1'000'000.0};
    // Another sensor's range (0 < min_us <= max_us, finite; std::invalid_argument otherwise).
    void set_exposure_range_us(drivers::ExposureRange range);
    // The trigger input (wired to SimTrigger); ignored while stopped or in
    // software trigger mode, as on a real camera.
    void line_trigger(std::int64_t t_ns);
    // Called at every start(), before streaming: where the scene may change
    // between scans (a person moving the board between button presses).
    void on_start(std::function<void()> hook);
    // Renders with `renderer` from the next exposure on; it must outlive the
    // camera and have the same camera size (std::invalid_argument otherwise).
    void set_renderer(const Renderer& renderer);
    // Frame ids from `next` on, counting as a GigE Vision 1.x camera's 16-bit
    // block id does (65535 is followed by 1) when `wrap_16_bit`.
    void set_next_frame_id(std::uint64_t next, bool wrap_16_bit);
    // Fault at the `at_trigger`-th trigger (0-based) since construction.
    void inject_fault(CameraFault fault, int at_trigger);
    // Every exposure taken, in order.
    // (The newest ones only, once limited; exposures_taken() counts them all.)
    const std::vector<Exposure>& exposures() const { return exposures_.items(); }
    std::size_t exposures_taken() const { return exposures_.total(); }
    void limit_records(std::size_t limit) { exposures_.set_limit(limit); }
    bool streaming() const { return streaming_; }

private:
    void expose(std::int64_t t_ns);
    void check_present() const;
    const Renderer* renderer_;
    std::function<void()> on_start_;
    const Screen& display_;
    drivers::Clock& clock_;
    drivers::CameraSettings settings_;
    drivers::ExposureRange exposure_range_ = kDefaultExposureRange;
    double nominal_exposure_us_;
    std::uint64_t seed_;
    bool streaming_ = false;
    bool gone_ = false;
    std::uint64_t next_frame_id_ = 1;
    bool wrap_16_bit_ = false;
    int triggers_ = 0;
    CameraFault fault_ = CameraFault::none;
    int fault_at_ = -1;
    struct Pending {
        Exposure exposure;
        bool incomplete = false;
    };
    std::deque<Pending> queue_;
    RecordLog<Exposure> exposures_;
    Image<std::uint8_t> dark_; // projector off
};

} // namespace fpp::sim
