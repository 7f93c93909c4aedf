#pragma once
// The projector as seen by the scan: a fixed set of pattern buffers rendered
// once, shown one at a time by page flips. The flip event is the moment the
// pattern is on screen; nothing is captured before it.
//
// Threading: one thread owns a Display. Errors at run time throw DeviceError.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <fpp/image.hpp>

namespace fpp::drivers {

// A completed page flip.
struct FlipEvent {
    std::size_t index = 0;         // pattern index passed to show()
    std::uint64_t sequence = 0;    // display vblank sequence number of the flip
    std::int64_t timestamp_ns = 0; // when the pattern went on screen (CLOCK_MONOTONIC, ns)
};

class Display {
public:
    virtual ~Display() = default;
    Display(const Display&) = delete;
    Display& operator=(const Display&) = delete;

    // Projector resolution in pixels (the mode's active area).
    virtual Size size() const = 0;

    // Allocate one scan-out buffer per pattern and render it once. Each
    // pattern is 8-bit single-channel at size(). Replaces earlier buffers; must
    // not be called while a flip is pending.
    virtual void prepare(const std::vector<Image<std::uint8_t>>& patterns) = 0;

    // Queue a page flip to pattern `index` (< number prepared). Non-blocking.
    // At most one flip may be pending: throws DeviceError if one is, or if the
    // flip cannot be queued.
    virtual void show(std::size_t index) = 0;

    // Wait for the pending flip to complete. Throws DeviceError on timeout,
    // on failure, or when no flip is pending.
    virtual FlipEvent wait_flip(std::chrono::milliseconds timeout) = 0;

    // Put the display back as it was found (the console's framebuffer and
    // mode). Safe to call more than once; destructors call it too.
    virtual void restore() = 0;

protected:
    Display() = default;
};

} // namespace fpp::drivers
