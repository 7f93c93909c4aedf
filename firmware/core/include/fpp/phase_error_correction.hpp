#pragma once
// Data-only correction of the periodic phase error that a non-linear
// projector (or camera) response leaves in N-step phase shifting, for
// captures whose response was never measured.
//
// Why it works: with any response f(drive level) the captured waveform of an
// N-step block is an even function of the true phase theta (the pattern's
// argument 2 pi p / period + phase_offset, fpp/pattern_block.hpp), so the
// decoded phase is theta + e(theta) with e odd and periodic in 2 pi / N
// (relabelling the frames shifts theta by 2 pi / N). Fold the phase into
// sub-periods: u = frac(N theta / (2 pi)) in [0, 1). Were the true u uniform
// over the pixels, the cumulative distribution F of the decoded u would be
// the map from decoded to true u, F(u) = u + c(u) + constant, and the
// Fourier coefficients of c follow from the decoded values alone
// (integration by parts; the constant is fixed by a zero-mean c):
//   c(u) = sum_k b_k sin(2 pi k u) + a_k cos(2 pi k u),
//   b_k = E[cos(2 pi k u)] / (pi k),  a_k = -E[sin(2 pi k u)] / (pi k),
// and the correction is p <- p + (period / N) c(u), p in projector pixels
// (pixel centres on integers). c is periodic: no seam at u = 0 / 1. Under
// the model above a_k = 0 (e is odd); real projectors leave a small cosine
// part too (see PhaseErrorOptions::odd_only).
//
// The true u is not quite uniform: a scene of few fringes covers some
// sub-periods partly, and a camera pixel grid that samples the fringes at a
// near-rational step (a fronto-parallel plane, or 2 pixels per sub-period)
// favours some phases (measured in simulation: 0.002 to 0.004 sub-periods of
// spurious c, as much as a gamma leaves with 4 steps). So the estimate
// measures that sampling bias too: a smooth stand-in for the true coordinate
// at each pixel, the value at the pixel of the least-squares plane through
// the once-corrected coordinates of a box about two sub-periods wide (exact
// for a locally linear coordinate; over whole sub-periods the periodic error
// averages out), has the same sampling as the pixel but little of the
// error; the moments of its fold are subtracted from those of the decoded
// fold over the same pixels. Where the pixel grid aliases a harmonic (the
// box cannot average it: "leakage" near 1), the sine part of the bias at
// that harmonic stays hidden; its likely size (the cosine part, always
// seen) is reported, and the correction refused when it is not small.
//
// The correction is applied at each pixel's stand-in fold where it has one
// (apply_phase_error_correction): c at the decoded fold would scale the
// pixel's noise by the slope 1 + c'(u).
//
// Frames and units: p and every *_px figure in projector pixels; u and the
// coefficients in sub-periods (period / N projector pixels).

#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace fpp {

class ThreadPool;

struct PhaseErrorOptions {
    // Harmonics of the sub-period in c(u). 3 steps under a gamma of 2.2
    // leave, after 6 / 8 / 12 terms, about 1.2 / 0.4 / 0.06 % of a
    // sub-period of the error they remove.
    int harmonics = 8;
    // The estimate needs this many valid pixels ...
    std::size_t min_pixels = 4000;
    // ... spread over this many sub-periods (each with >= 4 valid pixels).
    int min_sub_periods = 12;
    // c must keep the fold monotonic with margin: 1 + c'(u) >= min_slope
    // everywhere (3 steps under gamma 2.2 reach 0.45, under gamma 3 0.22;
    // an aliased scene produces folds).
    double min_slope = 0.1;
    // A bias the estimate cannot remove (the part of the sampling bias the
    // pixel grid hides; with odd_only, the cosine part the model excludes)
    // may be at most this fraction of the correction's RMS, unless below
    // bias_floor (sub-periods).
    double max_bias_ratio = 0.5;
    double bias_floor = 0.002;
    // Subtract the sampling bias measured with the smooth stand-in (above).
    // Off: the plain distribution estimate over every valid pixel (in
    // simulation it then corrects a linear projector on a fronto-parallel
    // plane by up to 0.014 px; with it, 0.003 px).
    bool debias_sampling = true;
    // Apply the sine (odd) part only, the part a response non-linearity
    // alone produces; the cosine part then serves as a check of that model.
    // Off: both. On SLStudio's real frames the cosine part is real (its
    // third harmonic is the same in five of six poses) and applying it
    // lowers the periodic residual on the board's white squares from 0.033
    // to 0.027 px (mean of six poses), so it is applied by default.
    bool odd_only = false;
    // Throws std::invalid_argument naming the field if a value is out of range.
    void validate() const;
};

struct PhaseErrorSummary {
    bool attempted = false; // an estimate was made (the option was on, the axis coded)
    bool applied = false;   // the correction passed the checks (and, after
                            // correct_phase_error, was applied)
    std::string reason;     // why not applied; empty when applied
    int steps = 0;          // N of the finest phase block
    double period = 0;      // its period, projector pixels
    std::size_t pixels = 0; // valid pixels the estimate used (with debias_sampling:
                            // those with a stand-in that agrees with them)
    int sub_periods = 0;    // distinct sub-periods with >= 4 of them
    int box_radius = 0;     // half-width of the stand-in's box, camera pixels (0: not used)
    bool odd_only = false;  // the cosine part is reported, not applied
    // c(u) = sum_k sine[k-1] sin(2 pi k u) + cosine[k-1] cos(2 pi k u),
    // k = 1..harmonics, sub-periods (zero mean: no constant term).
    std::vector<double> sine;
    std::vector<double> cosine;
    double rms_px = 0;       // RMS of the applied (period / N) c(u) over u, projector pixels
    double peak_px = 0;      // its largest magnitude, projector pixels
    double asymmetry_px = 0; // RMS of the cosine part alone, projector pixels
    // With debias_sampling: the sampling bias measured and removed (RMS,
    // projector pixels), the part of it the pixel grid hides (aliasing), and
    // the leakage of each harmonic into the stand-in (0 = none, 1 = all).
    double sampling_bias_px = 0;
    double aliasing_px = 0;
    std::vector<double> leakage;
    double min_slope = 1; // min over u of 1 + c'(u)
    // After correct_phase_error: the fraction of the corrected coordinates
    // that took the correction at their stand-in's fold (0 when not applied).
    double at_stand_in = 0;
};

// Estimates c from the pixels that are kDecodeValid in `mask` with a finite
// coordinate in `proj` (one axis, decoded with `finest` as its finest phase
// block), and judges it by `options`. Does not change `proj`. `pool`: workers
// (null = the calling thread); the result does not depend on it. Throws
// std::invalid_argument if the sizes differ, `finest` has fewer than 3 steps
// or a non-positive period, or the options are invalid.
PhaseErrorSummary estimate_phase_error(const Image<float>& proj, const Image<std::uint8_t>& mask,
                                       const PhaseBlock& finest,
                                       const PhaseErrorOptions& options = {},
                                       ThreadPool* pool = nullptr);

// Corrects every finite coordinate of `proj` if `summary.applied`;
// otherwise leaves it unchanged. NaN stays NaN. A pixel whose stand-in (the
// plane through its 3 x 3 box's corrected coordinates) agrees with it gets
// the correction at the stand-in's fold, the true fold with a third of the
// noise (c(u) taken at the decoded fold would scale the pixel's noise by
// 1 + c'(u), up to 1.8x with 3 steps under gamma 2.2); the others get
// (period / N) c(u) at their decoded fold u. Returns the fraction of finite
// coordinates corrected at their stand-in.
double apply_phase_error_correction(Image<float>& proj, const PhaseBlock& finest,
                                    const PhaseErrorSummary& summary, ThreadPool* pool = nullptr);

// Both: estimate, then apply when the checks pass.
PhaseErrorSummary correct_phase_error(Image<float>& proj, const Image<std::uint8_t>& mask,
                                      const PhaseBlock& finest,
                                      const PhaseErrorOptions& options = {},
                                      ThreadPool* pool = nullptr);

// c(u) in sub-periods, for u in sub-periods (any real; periodic in 1).
double phase_error_correction_at(const PhaseErrorSummary& summary, double u);

// The fold position of projector coordinate p: frac(N (p / period +
// phase_offset / (2 pi))), in [0, 1).
double phase_error_fold(const PhaseBlock& finest, double p);

// One line for reports, e.g. "applied: 0.412 px RMS, 0.583 px peak (N = 3,
// period 20 px; 81234 pixels over 188 sub-periods)" or "not applied: ...".
std::string describe(const PhaseErrorSummary& summary);

} // namespace fpp
