#pragma once
// Why nearly nothing decoded: found by measuring, not guessing.
//
// When a decode is suspect (less than 90 % of the lit pixels decoded,
// decode_suspect in fpp/decode_report.hpp), the capture is decoded again, with the same decoder and
// options, on a copy subsampled every 4th pixel in x and y (1/16 of the cost of a decode per
// trial), once per plausible mistake in the capture's description:
//   - frames that use few bits of their depth (largest sample below a quarter
//     of full scale): the samples scaled up to the full depth (what declaring
//     `bit_depth` does for 16-bit frames; an underexposure for 8-bit ones);
//   - the shift direction reversed: shift_sign flipped in one phase block, and
//     in every phase block at once;
//   - frames out of order: a phase block's frames reversed, rotated
//     cyclically, or two neighbours swapped; a code block's planes reversed;
//     two phase blocks of one axis swapped;
//   - the period not the frames' fringe frequency: a phase block's period read
//     as a fringe count across the projector (extent / period, the way
//     "1920/58" is often written).
// Each trial's coverage is that of the pixels the declared decode found lit.
// A trial that decodes at least 50 % of them and 25 points more than the
// declared sequence is named ("with shift_sign -1 in sequence[1], 97 % of lit
// pixels decode instead of 3 %"); otherwise the message says what was measured
// (what is lit, the main reason pixels were dropped, the best trial).
//
// The decode has failed when nearly nothing decoded (nearly_nothing_decoded)
// or when a trial is named: the capture's description is then evidently wrong,
// and the pixels it "decoded" carry wrong coordinates the unwrapping checks
// happened to accept (a reversed shift leaves 40-70 % of them).

#include "fpp/capture_set.hpp"
#include "fpp/decode_report.hpp"
#include "fpp/decoder.hpp"

#include <string>
#include <vector>

namespace fpp {

struct DecodeTrial {
    std::string change;     // "shift_sign -1 in sequence[1]"
    double coverage_of_lit; // on the subsampled copy, 0..1
};

struct DecodeDiagnosis {
    bool failed = false;             // nearly nothing decoded, or a trial named (see above)
    std::string message;             // what was measured and the likely cause; empty unless suspect
    std::vector<DecodeTrial> trials; // every trial made, in order
    int best_trial = -1;             // index into trials of the trial named, -1 = none
    int bits_in_use = 0;             // bits the largest sample needs
    int bits_declared = 0;           // bits of the frames' full scale (Frame::max_value)
};

// `result` and `stats` are the declared decode of `capture` with `options`.
// Runs no trial unless the decode is suspect.
DecodeDiagnosis diagnose_decode(const CaptureSet& capture, const DecodeResult& result,
                                const DecodeStatistics& stats, const DecodeOptions& options);

// The full scale of the bits the frames use, in DN, for the lit floor:
// Frame::max_value() of 8-bit frames and of 16-bit frames whose
// significant_bits is known; for other 16-bit frames 2^b - 1 with b the bits
// the largest sample needs (at least 8), since a 12-bit camera's frames stored
// in 16 bits leave the top of 65535 empty. 255 without frames.
double frames_full_scale(const CaptureSet& capture);

// The same on borrowed frames (make_capture_view): the same figures.
DecodeDiagnosis diagnose_decode(const CaptureView& capture, const DecodeResult& result,
                                const DecodeStatistics& stats, const DecodeOptions& options);
double frames_full_scale(const CaptureView& capture);

} // namespace fpp
