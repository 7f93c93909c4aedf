#pragma once
// What the projector shows, as the simulated camera needs to know it: which
// pattern is on screen at a given time and what that pattern looks like.
// SimDisplay is one; ObservedDisplay gives the same view of a real display.
#include <cstddef>
#include <cstdint>

#include <fpp/image.hpp>

namespace fpp::sim {

class Screen {
public:
    // Nothing on screen (the projector dark) before the first flip.
    static constexpr int kNothing = -1;

    virtual ~Screen() = default;
    // Pattern index on screen at time t_ns (the board clock's time), or kNothing.
    virtual int on_screen_at(std::int64_t t_ns) const = 0;
    // The prepared pattern image (projector size, 8-bit).
    virtual const Image<std::uint8_t>& pattern(std::size_t index) const = 0;

protected:
    Screen() = default;
    Screen(const Screen&) = default;
    Screen& operator=(const Screen&) = default;
};

} // namespace fpp::sim
