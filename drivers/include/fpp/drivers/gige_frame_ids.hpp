#pragma once
// Frame (block) id arithmetic of GigE Vision streams, kept apart from the
// driver so that it can be tested without a camera. The scan checks every
// camera's frames with it (a camera whose ids do not wrap passes as well).
//
// GVSP 1.x carries a 16-bit block id that counts 1, 2, ..., 65535 and then
// wraps to 1 (0 is reserved); GVSP 2.x extended ids are 64-bit and do not wrap
// in practice. Aravis reports either as a 64-bit frame id.
#include <cstdint>

namespace fpp::drivers {

// The id the camera gives the frame after `previous`.
constexpr std::uint64_t gige_next_frame_id(std::uint64_t previous) {
    if (previous == 0xFFFFu)
        return 1; // 16-bit wrap skips the reserved 0
    return previous + 1;
}

// Frames lost between `previous` and `id` (0 when `id` follows directly).
// An id that does not lie ahead of `previous` within half the 16-bit range
// (a repeat or a step back) is reported as UINT64_MAX.
constexpr std::uint64_t gige_frames_missed(std::uint64_t previous, std::uint64_t id) {
    if (previous <= 0xFFFFu && id <= 0xFFFFu && id < previous && previous - id > 0x8000u) {
        // 16-bit wrap: ids previous+1 .. 65535 and 1 .. id-1 are missing.
        if (id == 0)
            return UINT64_MAX;
        return (0xFFFFu - previous) + (id - 1);
    }
    if (id <= previous)
        return UINT64_MAX;
    return id - previous - 1;
}

} // namespace fpp::drivers
