#pragma once
// Projector pattern generation, exactly the spec's formulas, 8-bit.

#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace fpp {

// Ideal intensity in [0, 1] of frame `frame` of `block` at projector pixel
// (x, y) (pixel centres on integers). White = 1, black = 0.
double pattern_intensity(const PatternBlock& block, int frame, double x, double y);

struct ProjectorResponse;

// Maps a wanted relative intensity (index = round(255 v)) to the 8-bit drive
// level that makes the projector emit it.
struct GammaLut {
    std::array<std::uint8_t, 256> level{};
    static GammaLut identity();
    // For a projector with response (level/255)^gamma.
    static GammaLut precompensate(double projector_gamma);
    // For a measured response (fpp/projector_response.hpp): each v = i/255
    // gets the drive level whose emitted light is nearest v^emitted_gamma
    // (the lower level on a tie). emitted_gamma 1: the inverse of the
    // response, a linear projector. Throws InputError for an invalid
    // response, std::invalid_argument for emitted_gamma outside [1, 4].
    static GammaLut from_response(const ProjectorResponse& response, double emitted_gamma = 1.0);
};

// The emitted_gamma of GammaLut::from_response that suits `sequence`: 2 when
// every phase block has 4 or more steps, else 1. Squared fringes,
// (1/2 + 1/2 cos x)^2 = 3/8 + 1/2 cos x + 1/8 cos 2x, keep the linear
// fringe's amplitude with a quarter less light (less shot noise) and add only
// a second harmonic, which N-step phase shifting cancels for N >= 4 (it
// aliases onto the phase for N = 3 alone).
double compensation_emitted_gamma(const Sequence& sequence);

// Renders one frame at projector resolution: value = round(255 * I) mapped
// through `lut` when given.
Image<std::uint8_t> render_pattern(const PatternBlock& block, int frame, Size projector,
                                   const GammaLut* lut = nullptr);

// Renders every frame of a sequence in capture order.
std::vector<Image<std::uint8_t>> render_sequence(const Sequence& sequence, Size projector,
                                                 const GammaLut* lut = nullptr);

} // namespace fpp
