#pragma once
// The camera driver over Aravis 0.8 (GigE Vision and USB3 Vision cameras).
//
// Configuration uses the standard GenICam feature names: PixelFormat,
// ExposureTime (ExposureTimeAbs on older cameras), TriggerSelector=FrameStart,
// TriggerMode=On, TriggerSource (Software or the configured line),
// AcquisitionMode=Continuous and, on GigE cameras, the stream packet size.
//
// Frames are checked as they arrive: the frame id must follow the previous one
// (a gap names the missing ids), the camera timestamp must increase, the
// buffer must be complete and of the configured size and format. Every check
// that fails throws DeviceError; the buffer goes back to the stream in every
// case.
//
// Pixel formats: Mono8 -> 8-bit frames; Mono10, Mono12, Mono14, Mono16
// (unpacked, little-endian) -> 16-bit frames, MSB-aligned like the rest of
// fpp (a 12-bit sample s becomes s << 4).
//
// CapturedFrame::timestamp_ns is the host's arrival time of the frame mapped to
// CLOCK_MONOTONIC (the camera's own clock is not synchronised with the host);
// frame_id is the camera's block id (16-bit GigE ids wrap from 65535 to 1).
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include <fpp/drivers/camera.hpp>

namespace fpp::drivers {

class AravisCamera final : public Camera {
public:
    // `device`: an Aravis device id (as listed by arv-tool, e.g.
    // "Aravis-Fake-GV01") or the camera's IPv4 address ("192.168.1.20"). Opening
    // by address reaches a GigE camera without discovery. Throws DeviceError if
    // the camera cannot be reached or lacks a feature the settings need, and
    // fpp::InputError("camera settings", field, ...) for a value out of range
    // (exposure_us: outside the camera's ExposureTime bounds, named).
    AravisCamera(const std::string& device, const CameraSettings& settings);
    ~AravisCamera() override;

    Size size() const override;
    int bit_depth() const override;
    void start() override;
    void stop() override;
    // The camera's ExposureTime (or ExposureTimeAbs) bounds, read when opened.
    ExposureRange exposure_range_us() const override;
    void set_exposure_us(double exposure_us) override;
    void software_trigger() override;
    CapturedFrame next_frame(std::chrono::milliseconds timeout) override;
    std::size_t frames_waiting() const override;

    // "camera <device>", the name used in DeviceError messages.
    const std::string& name() const;
    // Buffers in the stream pool and how many are held outside the stream
    // (always 0 between calls: buffers go back before next_frame returns).
    int buffer_count() const;
    int buffers_outstanding() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace fpp::drivers
