#pragma once
// High dynamic range by exposure fusion after decoding: the same sequence
// decoded once per exposure, then per camera pixel the passes that decoded it
// are combined by their predicted coordinate noise (fpp/phase_noise.hpp).
//
// Per pixel: the pass with the smallest predicted sigma is the reference;
// every pass that decoded the pixel and agrees with it on each coded axis
// within 3 combined sigma is averaged with weight 1 / sigma^2 (the passes'
// noise is independent), so the fused sigma is 1 / sqrt(sum of weights).
// A pass whose coordinate disagrees (a wrong fringe order, a clipped sample
// that escaped the saturation test) is left out. A pixel that no pass
// decoded keeps the flags of every pass OR-ed (without kDecodeValid): a pixel
// saturated at every exposure is flagged kDecodeSaturated and never decoded
// from clipped data, since each pass's decoder already refuses it.
//
// Modulation and mean of the fused result are the reference pass's, scaled
// to the first pass's exposure (DN at that exposure: an HDR radiance, above
// full scale where the first pass clipped).

#include "fpp/decoder.hpp"
#include "fpp/image.hpp"

#include <cstddef>
#include <vector>

namespace fpp {

class ThreadPool;

struct ExposurePass {
    DecodeResult decoded;
    double exposure_us = 0;
    Image<float> sigma; // predicted sigma of the coordinate (projector px), camera size
};

struct FusionStats {
    std::vector<std::size_t> reference_pixels; // per pass: pixels where it was the reference
    std::size_t averaged = 0;                  // pixels averaged over two passes or more
    std::size_t disagreeing = 0;               // pass values left out for disagreeing
    std::size_t undecoded = 0;                 // pixels no pass decoded
};

// Fuses `passes` (at least one, all of the same camera size and sequence)
// into `out` (its images reused when their size fits) and the fused sigma
// into `sigma`. Throws std::invalid_argument for an empty list, passes of
// different sizes or a sigma image of another size.
FusionStats fuse_exposures(const std::vector<ExposurePass>& passes, DecodeResult& out,
                           Image<float>& sigma, ThreadPool* pool = nullptr);

} // namespace fpp
