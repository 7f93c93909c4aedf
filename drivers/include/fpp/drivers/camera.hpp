#pragma once
// The camera as seen by the scan: configured once, started, then one frame per
// trigger. Errors at run time (timeout, camera gone, incomplete frame) throw
// DeviceError; the caller fails the scan and may retry it.
//
// Threading: one thread owns a Camera.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>

#include <fpp/enum_names.hpp>
#include <fpp/image.hpp>

namespace fpp::drivers {

enum class TriggerMode {
    software, // software_trigger() starts each exposure
    line,     // a hardware line (see CameraSettings::trigger_source) does
};
// The board file's and scan.json's names.
inline constexpr EnumName<TriggerMode> kTriggerModeNames[] = {{TriggerMode::line, "line"},
                                                              {TriggerMode::software, "software"}};

struct CameraSettings {
    std::string pixel_format = "Mono8"; // GenICam PixelFormat name: Mono8, Mono10, Mono12, Mono16
    double exposure_us = 10000.0;       // exposure time, microseconds
    TriggerMode trigger = TriggerMode::line;
    std::string trigger_source = "Line0"; // GenICam TriggerSource for TriggerMode::line
    int packet_size = 0;                  // GigE stream packet size in bytes; 0 = driver default
    int buffer_count = 4;                 // buffers in the stream pool
    std::chrono::milliseconds frame_timeout{1000}; // default wait in next_frame()
};

// Exposure times a camera accepts, microseconds, both bounds included.
struct ExposureRange {
    double min_us = 0;
    double max_us = 0;
    bool contains(double exposure_us) const {
        return exposure_us >= min_us && exposure_us <= max_us;
    }
};

struct CapturedFrame {
    Frame frame;
    std::uint64_t frame_id = 0;    // camera's frame counter (consecutive while streaming)
    std::int64_t timestamp_ns = 0; // exposure start (CLOCK_MONOTONIC, ns) when known
};

class Camera {
public:
    virtual ~Camera() = default;
    Camera(const Camera&) = delete;
    Camera& operator=(const Camera&) = delete;

    // Sensor region read out, pixels.
    virtual Size size() const = 0;
    // Container depth of delivered frames: 8 or 16.
    virtual int bit_depth() const = 0;

    // Start / stop acquisition. After start() each trigger yields one frame.
    // stop() is safe when already stopped; buffers go back to the driver.
    virtual void start() = 0;
    virtual void stop() = 0;

    // The exposure times set_exposure_us() accepts (the camera's own bounds,
    // fixed while the camera is open).
    virtual ExposureRange exposure_range_us() const = 0;

    // Exposure time of the frames from the next start() on. Checked:
    // InputError(settings origin, "exposure_us", ...) naming the range for a
    // value outside exposure_range_us(); DeviceError when the camera cannot be
    // reached or refuses it, or while streaming. Only while stopped.
    virtual void set_exposure_us(double exposure_us) = 0;

    // Fire one exposure from software. Only valid with TriggerMode::software;
    // throws DeviceError otherwise or when the camera is gone.
    virtual void software_trigger() = 0;

    // Wait up to `timeout` for the next frame. Throws DeviceError on timeout,
    // camera gone or an incomplete frame.
    virtual CapturedFrame next_frame(std::chrono::milliseconds timeout) = 0;
    // Frames arrived (complete or not) that next_frame() has not taken yet.
    // Before a trigger it is 0: a frame there is one no trigger of the scan
    // asked for (a software trigger command repeated after its lost
    // acknowledgement fires the camera twice; so does a glitch on the line).
    virtual std::size_t frames_waiting() const = 0;

protected:
    Camera() = default;
};

} // namespace fpp::drivers
