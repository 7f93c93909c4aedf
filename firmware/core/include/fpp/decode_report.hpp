#pragma once
// What a decode did, counted: which camera pixels were lit, how many of them
// decoded, and why each of the others was dropped. Shared by fpp-calib decode
// / reconstruct and the scanner's scan.json, so both say the same thing.
//
// Lit: a pixel is lit when its fringe modulation B (DecodeResult::modulation,
// camera DN; for code-only sequences the decoder's white-black contrast) is
// at or above the noise floor, when it is flagged saturated (blown out: lit,
// whatever its modulation), or when it decoded.
//
// The floor (camera DN) comes from the data. The modulation that noise alone
// gives a dark pixel follows a Rayleigh distribution whose mode is its scale
// sigma. When the histogram of B (bins of full_scale / 2048 over
// [0, full_scale / 8)) has a peak at or below full_scale / 64 that falls to
// half its height before three times its position and stands at least 0.3 of
// its height at half its position (a dark mode: background, shadows), sigma = that mode and the
// floor is 5 sigma (a dark pixel lies above it with probability exp(-12.5), 4e-6), at least
// full_scale / 256 (one step of 8-bit data). Pixels whose modulation is exactly 0 (every frame
// equal: clipped at black) carry no noise and are left out of the histogram.
// Without a dark mode (the whole view lit) the floor is 1 % of full scale.
//
// Every pixel is counted once, in this order: decoded; dark (not lit);
// saturated; low modulation; code and phase disagree
// (kDecodeUnwrapInconsistent); out of range (kDecodeOutOfRange); no cue
// (kDecodeNoCue); other (not decoded, no flag). The counts add up to the
// image.

#include "fpp/decoder.hpp"

#include <cstddef>
#include <string>
#include <vector>

namespace fpp {

struct DecodeStatistics {
    std::size_t pixels = 0; // camera pixels (width x height)
    double full_scale = 0;  // DN, the frames' full scale the floor rule used
    double lit_floor = 0;   // DN: modulation at or above it is lit
    double dark_sigma = 0;  // DN: Rayleigh scale of the dark mode; 0 without one
    bool floor_from_dark_mode = false;
    std::size_t lit = 0; // lit pixels (decoded ones included)
    // Each pixel in exactly one of these (the precedence above).
    std::size_t decoded = 0;
    std::size_t dark = 0;
    std::size_t saturated = 0;
    std::size_t low_modulation = 0;
    std::size_t unwrap_inconsistent = 0;
    std::size_t out_of_range = 0;
    std::size_t no_cue = 0;
    std::size_t other = 0;

    // decoded / lit, 0 when nothing is lit.
    double coverage_of_lit() const;
    // The sum of the per-reason counts and decoded (== pixels).
    std::size_t counted() const;
    // One line: "lit floor 3.1 DN (5 sigma of the dark pixels' modulation)".
    std::string floor_rule() const;
};

// Counts `result` by the rules above. `full_scale`: the frames' full scale in
// DN (Frame::max_value(): 255, 4095, 65535). Throws
// InputError("decode_statistics", "full_scale" or "mask", ...) when
// full_scale is not > 0 or the result's mask is empty. A result without a
// modulation image counts every pixel as lit (floor 0).
DecodeStatistics decode_statistics(const DecodeResult& result, double full_scale);

// The same for the fusion of several exposures of one scene
// (fpp/exposure_fusion.hpp), whose undecoded pixels carry no modulation: a
// pixel is lit when it is lit in any pass (each pass with its own floor),
// decoded when the fused result is, and otherwise counted by the fused flags
// (every pass's flags ORed). The floor reported is the first pass's. Throws
// as decode_statistics does, and InputError("fused_decode_statistics",
// "passes[i]", ...) for a pass that is null or of another size.
DecodeStatistics fused_decode_statistics(const DecodeResult& fused,
                                         const std::vector<const DecodeResult*>& passes,
                                         double full_scale);

// Coverage below which a decode counts as failed ("nearly nothing decodes"):
// less than 10 % of the lit pixels decoded, or less than 1 % of the image lit.
inline constexpr double kFailedCoverageOfLit = 0.10;
inline constexpr double kFailedLitFraction = 0.01;
bool nearly_nothing_decoded(const DecodeStatistics& stats);
// Coverage below which a decode is worth a diagnosis (fpp/decode_diagnosis.hpp):
// a capture whose description is wrong (shift direction, frame order) often
// still "decodes" 40-70 % of its lit pixels, to wrong coordinates that the
// unwrapping checks happen to accept.
inline constexpr double kSuspectCoverageOfLit = 0.90;
bool decode_suspect(const DecodeStatistics& stats);

} // namespace fpp
