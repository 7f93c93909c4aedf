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
//                                             ("inverse-" prefix with inverse frames,
//                                             "binary" for natural binary, "shifted-"
//                                             prefix with an offset, "-L-level" suffix)
//   several phase blocks, coarsest covers the projector extent -> "multi-period"
//   several phase blocks otherwise (2 or 3, beat covers the extent) -> "heterodyne"
//   one phase block covering the extent    -> "direct"
//   one phase block + centerline           -> "centerline" (spatial unwrapping made
//                                             absolute by the centerline pixels)
//   a gray block and no phase block        -> "gray-code" / "binary-code" (code only;
//                                             "inverse-", "shifted-", "-L-level" as above)
//   a micro_phase block (alone on its axis) -> "micro-phase"
// A phase block of any shifting (standard, 2+1, modulated) unwraps with every
// method above; its period may be any positive number (1920/58 = 33.10... px).
//   2+1 (frames sin, cos, flat): theta = atan2(shift_sign (I0 - I2), I1 - I2),
//     A = I2, B = hypot(...).
//   modulated (N shifts x M carrier shifts): per shift i the carrier amplitude
//     D_i = (2/M) |sum_j I_ij e^{-i 2 pi j / M}|, then the standard N-step on
//     the D_i. Light that carries no carrier (ambient, global / indirect light
//     that blurs the carrier away) drops out of D_i; A and B are those of the
//     D_i (about a quarter of the white level each); a gray block thresholded
//     against this block uses the mean of all its frames plus A (= ambient +
//     half the white level).
//   micro phase (Gupta and Nayar 2012, decode_micro.hpp): A, B and the first
//     period's phase from its three shifted frames; each fringe order k of
//     the first period inside the projector, p = (phase / 2 pi + k) P_1, is
//     scored by the least-squares fit of A' + B' cos(predicted phase) to all
//     frames; the best fit gives the column. A pixel whose second-best order
//     fits worse by less than 0.0013 full scale^2 (85 DN^2 at 8 bits) is
//     flagged kDecodeUnwrapInconsistent.
// Gray planes are thresholded against (white + black) / 2 when the sequence has
// both, against their inverse frames when present, else against the mean A of
// the phase block they index. n-ary digits (levels L > 2; white and black
// required) are round((I - black) / (white - black) (L - 1)), clamped. Digits
// are read MSB first or LSB first as the block says; Gray (reflected L-ary) or
// natural code values become the code step n; step n covers projector
// [offset + n u, offset + (n + 1) u) (u = period, or period / 2 for
// complementary code), and code values that no step inside the projector uses
// are the wrapped steps left of the offset (n - L^digits). With a phase block,
// the fringe order is the one that puts p nearest the centre of the code's
// interval [ceil(offset + K u) - 0.5, ceil(offset + (K + 1) u) - 0.5]: code
// edges sit between projector pixels, the phase wraps at multiples of the
// period (a shifted code, offset = period / 2, puts the edges mid-fringe).
// Plain Gray pixels near a code edge are checked against their neighbours.
// Code only: p is the centre of the projector pixels that show step n,
// (ceil(offset + n u) + ceil(offset + (n + 1) u)) / 2 - 1/2 (= offset +
// (n + 1/2) u - 1/2 for whole-pixel u and offset), so the error is the
// quantisation of the step on the pixel grid. The centerline method only
// reaches surfaces that carry the centerline; other regions get kDecodeNoCue.
// A sequence that cannot be decoded (no phase or gray block, a phase block
// without a usable cue, a gray block with too few digits, a code-only block
// without inverse or white/black frames, more than one gray or centerline
// block on an axis, ...) makes the constructor / decode() throw
// fpp::InputError (fpp/error.hpp) naming the block and the reason: its file
// is the capture's manifest (decode(): capture.folder / "capture.yaml") or
// kDecoderOrigin (StreamingDecoder, which reads no file); its field names
// the block as the capture-set reader does, "sequence[2].period" (or
// "sequence[2]" for the block as a whole, "sequence" for the sequence,
// "camera" / "projector" for a size); its message begins "cannot decode
// sequence: ".
//
// Coordinates outside the projector (beyond one pixel of margin) are flagged
// kDecodeOutOfRange; code and phase that disagree (or an unused code value, an
// ambiguous micro-phase column) kDecodeUnwrapInconsistent. Low modulation and
// saturation are judged on the phase frames a pixel uses (see DecodeOptions).
// Code-only axes: low modulation where (white - black) / 2 (white/black) or
// the largest |I - I_inverse| / 2 over the planes (inverse) is below
// min_modulation, or where two or more planes lie within min_modulation of
// full scale of their decision boundary (|I - threshold|, |I - I_inverse| / 2,
// or the distance to an n-ary level boundary): Gray codes change one digit
// between neighbouring steps, so two doubtful digits mean a code edge that
// cannot be resolved (natural binary) or no contrast. Their
// DecodeResult::modulation and mean are that half contrast and the threshold
// ((white + black) / 2, or (I + I_inverse) / 2 of the first plane).

#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"
#include "fpp/phase_error_correction.hpp"

#include <cstdint>
#include <memory>
#include <string>

namespace fpp {

// The "file" of the InputErrors of the streaming decoder (which has no
// manifest) and of DecodeOptions::validate().
inline constexpr const char* kDecoderOrigin = "decoder";
inline constexpr const char* kDecodeOptionsOrigin = "decode options";

struct DecodeOptions {
    // A pixel is valid only if the modulation B of every phase block it uses is
    // at least this fraction of the frames' full scale, Frame::max_value() of
    // the first frame: 2^bits - 1 of the bits in use (255, 4095 for 12-bit
    // data in 16-bit frames, 65535).
    double min_modulation = 0.02;
    // A sample at or above this fraction of full scale (as above) counts as
    // saturated. 0.999 catches 255 in 8-bit frames, 4095 of LSB-aligned 12-bit
    // data, and the MSB-aligned maxima of 10- and 12-bit sensors in 16-bit
    // frames read as 16 bits (65472, 65520).
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
    // Micro phase shifting: score every fringe order at every pixel (the
    // maximum-likelihood decision alone). By default most pixels try only the
    // orders their row's samples found (see decode_micro.cpp), about 3x
    // faster, and keep an order those samples confirm where a far order fits
    // nearly as well (more pixels decoded, no more gross errors measured).
    bool micro_every_order = false;

    // Throws InputError(kDecodeOptionsOrigin, field, "must be ...") naming the
    // field ("min_modulation", "threads", ...; "phase_error" for a value of
    // phase_error, the message naming it) if a value is out of range.
    void validate() const;
};

// Per-pixel flags in DecodeResult::mask.
enum DecodeFlag : std::uint8_t {
    kDecodeValid = 1 << 0,
    kDecodeLowModulation = 1 << 1,
    kDecodeSaturated = 1 << 2,
    kDecodeUnwrapInconsistent = 1 << 3,
    kDecodeNoCue = 1 << 4,      // e.g. spatial unwrapping region without a centerline
    kDecodeOutOfRange = 1 << 5, // decoded coordinate outside the projector (beyond the margin)
};

struct DecodeResult {
    Size camera;
    Image<float> proj_x;      // empty if the sequence codes no x
    Image<float> proj_y;      // empty if the sequence codes no y
    Image<float> modulation;  // B of the finest phase block (first coded axis), DN;
                              // code-only axis: its half contrast (see above)
    Image<float> mean;        // A of the same block, DN; code-only: its threshold
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

    // Feeds the next frame in capture order. Throws InputError(kDecoderOrigin,
    // "frames[i]", ...) on a frame of the wrong size, a bit depth differing
    // from the first frame, or (field "frames") more frames than the sequence
    // has. The frame is not referenced after push() returns (frames needed
    // later are copied).
    void push(const Frame& frame);
    // Same, from borrowed samples (read during the call only).
    void push(const FrameView& frame);
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
// written once. Refusals are InputErrors: of the options as
// DecodeOptions::validate() throws them; of the sequence (as above) and of the
// frames (field "frames[i]", or "frames" for the wrong number of frames)
// naming capture.folder / "capture.yaml".
DecodeResult decode(const CaptureSet& capture, const DecodeOptions& options = {});
// Same, writing into `result` and reusing its images' memory when their size
// fits (bit-identical output to the form above; no page faults or zero-fill
// of fresh images, about an eighth of the decoding time at 1600x1200).
// If it throws, `result` is left empty or partly moved from.
void decode(const CaptureSet& capture, DecodeResult& result, const DecodeOptions& options = {});
// Same, on borrowed frames (a CaptureView: make_capture_view, view_of): the
// same result, bit for bit, as the CaptureSet holding the same samples; no
// sample copied.
DecodeResult decode(const CaptureView& capture, const DecodeOptions& options = {});

} // namespace fpp
