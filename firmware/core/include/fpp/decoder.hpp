#pragma once
// Fringe decoding: camera frames in, projector coordinates per camera pixel out.
// Batch (`decode`) and streaming (`StreamingDecoder`, frames pushed one at a
// time as they arrive) give bit-identical results.
//
// Conventions: projector coordinates in projector pixels, pixel centres on
// integers (firmware/core/formats/capture-set.md); intensities in camera DN; NaN where invalid.
//
// The unwrapping method of each axis follows from the sequence:
//   phase + gray block of the same period  -> "gray" / "complementary-gray"
//                                             ("inverse-" prefix with inverse frames)
//   several phase blocks, coarsest covers the projector extent -> "multi-period"
//   several phase blocks otherwise (2 or 3, beat covers the extent) -> "heterodyne"
//   one phase block covering the extent    -> "direct"
//   one phase block + centerline           -> "centerline" (spatial unwrapping made
//                                             absolute by the centerline pixels)
// Gray planes are thresholded against (white + black) / 2 when the sequence has
// both, against their inverse frames when present, else against the mean A of
// the phase block they index. The fringe order is the one that puts p nearest
// the centre of the code's interval [ceil(K u) - 0.5, ceil((K + 1) u) - 0.5]
// (u = period, or period / 2 for complementary code): code edges sit between
// projector pixels, the phase wraps at multiples of the period. Plain Gray
// pixels near a code edge are checked against their neighbours. The
// centerline method only reaches surfaces that carry the centerline; other
// regions get kDecodeNoCue.
// A sequence that cannot be decoded (no phase block, a phase block without a
// usable cue, a gray block without a phase block of its period or with too
// few bits, more than one gray or centerline block on an axis, ...) makes the
// constructor / decode() throw std::invalid_argument naming the reason.
//
// Coordinates outside the projector (beyond one pixel of margin) are flagged
// kDecodeUnwrapInconsistent. Low modulation and saturation are judged on the
// phase frames a pixel uses (see DecodeOptions).

#include "fpp/capture_set.hpp"
#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"
#include "fpp/phase_error_correction.hpp"

#include <cstdint>
#include <memory>
#include <string>

namespace fpp {

struct DecodeOptions {
    // A pixel is valid only if the modulation B of every phase block it uses is
    // at least this fraction of the frame's full scale (255 or 65535).
    double min_modulation = 0.02;
    // A sample at or above this fraction of full scale (255 or 65535) counts as
    // saturated. 0.999 catches 255 in 8-bit frames and the MSB-aligned maxima
    // of 10- and 12-bit sensors in 16-bit frames (65472, 65520).
    double saturation = 0.999;
    // Whether saturation in the thresholded frames (gray planes, white and
    // black, centerline) also invalidates a pixel. Off by default: clipping
    // bends a phase frame's sinusoid and biases the phase, but a clipped white
    // stripe still reads as white (in the SLMaster scan a fifth of the tile
    // clips in the Gray frames only and decodes correctly).
    bool saturation_in_binary_frames = false;
    // Largest tolerated disagreement, in periods of the finer block, between
    // a coarse cue and the fine phase before a pixel is flagged inconsistent.
    double max_unwrap_disagreement = 0.35;
    // Worker threads for per-pixel loops; 0 = all cores.
    int threads = 0;
    // Removes, from the data alone, the periodic phase error that a
    // non-linear projector or camera response leaves (fpp/phase_error_correction.hpp):
    // each coded axis from its finest phase block, after unwrapping. Changes
    // proj_x / proj_y only (never which pixels are valid); refused, with the
    // reason in DecodeResult::phase_correction_x / _y, when the scene does not
    // sample the phase well enough. For captures whose response was never
    // measured; off by default. It takes about 70 ms an axis at 1688 x 1352
    // on two cores and allocates its scratch memory on each decode.
    bool correct_phase_error = false;
    PhaseErrorOptions phase_error; // its settings (validated with the rest)

    // Throws std::invalid_argument naming the field if a value is out of range.
    void validate() const;
};

// Per-pixel flags in DecodeResult::mask.
enum DecodeFlag : std::uint8_t {
    kDecodeValid = 1 << 0,
    kDecodeLowModulation = 1 << 1,
    kDecodeSaturated = 1 << 2,
    kDecodeUnwrapInconsistent = 1 << 3,
    kDecodeNoCue = 1 << 4, // e.g. spatial unwrapping region without a centerline
};

struct DecodeResult {
    Size camera;
    Image<float> proj_x;      // empty if the sequence codes no x
    Image<float> proj_y;      // empty if the sequence codes no y
    Image<float> modulation;  // B of the finest phase block (first coded axis), DN
    Image<float> mean;        // A of the same block, DN
    Image<std::uint8_t> mask; // DecodeFlag bits; kDecodeValid set where every coded axis is valid
    std::string method_x;     // how x was unwrapped, e.g. "complementary-gray"
    std::string method_y;
    // The data-only phase-error correction of each axis
    // (DecodeOptions::correct_phase_error; attempted = false when off or the
    // axis is not coded).
    PhaseErrorSummary phase_correction_x;
    PhaseErrorSummary phase_correction_y;
};

class StreamingDecoder {
public:
    StreamingDecoder(const Sequence& sequence, Size camera, Size projector,
                     const DecodeOptions& options = {});
    // Same, reusing the image memory of a previous result (scan after scan:
    // no page faults or zero-filling of fresh images).
    StreamingDecoder(const Sequence& sequence, Size camera, Size projector,
                     const DecodeOptions& options, DecodeResult&& recycled);
    ~StreamingDecoder();
    StreamingDecoder(StreamingDecoder&&) noexcept;
    StreamingDecoder& operator=(StreamingDecoder&&) noexcept;

    // Feeds the next frame in capture order. Throws std::invalid_argument on a
    // frame of the wrong size, a bit depth differing from the first frame, or
    // more frames than the sequence has. The frame is not referenced after
    // push() returns (frames needed later are copied).
    void push(const Frame& frame);
    int frames_received() const;
    int frames_expected() const;
    // Completes decoding; throws std::logic_error if frames are missing or
    // if called twice. The decoder is spent afterwards, until restart().
    DecodeResult finish();
    // Starts over at the first frame of the sequence (after finish(), or to
    // abandon a sequence part-way), keeping the decoder's own memory (state
    // planes, frame slots) and reusing the images of `recycled`, a result of
    // finish(), when their size fits (of an abandoned sequence: its own). Scan
    // after scan, decoding then touches no fresh memory: no page faults.
    void restart(DecodeResult&& recycled = {});

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Batch form: the whole capture set at once. Works through the image in
// cache-sized spans of pixels, each taken through every frame and the
// unwrapping at once, so each input sample is read once and each output
// written once.
DecodeResult decode(const CaptureSet& capture, const DecodeOptions& options = {});
// Same, writing into `result` and reusing its images' memory when their size
// fits (bit-identical output to the form above; no page faults or zero-fill
// of fresh images, about an eighth of the decoding time at 1600x1200).
// If it throws, `result` is left empty or partly moved from.
void decode(const CaptureSet& capture, DecodeResult& result, const DecodeOptions& options = {});

} // namespace fpp
