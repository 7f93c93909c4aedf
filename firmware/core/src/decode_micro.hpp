#pragma once
// Micro phase shifting (Gupta and Nayar 2012): F closely spaced periods
// P_1 .. P_F in F + 2 frames, frames 0-2 the first period shifted by
// shift_sign 2 pi k / 3, frame 1 + f period P_f (f = 2 .. F) at phase_offset
// plus its extra_offsets entry. A, B and the first period's phase come from
// the three shifted frames. Each fringe order k of the first period gives a
// candidate column p = (frac_1 + k) P_1 inside the projector; the candidate
// is scored by the least-squares fit of I = A' + B' cos(2 pi p / P_j +
// delta_j) to all F + 2 frames (A', B' free), the maximum likelihood test in
// white noise. The three shifted frames contribute the same to every
// candidate, so only the F - 1 other frames are summed per candidate.
// A pixel is ambiguous (kDecodeUnwrapInconsistent) when the second-best
// order's residual exceeds the best's by less than kMicroMinGap full scale
// squared: the noise could have swapped them. Unless every_order is set,
// most pixels try only the orders of sampled neighbours (micro_search).

#include "decode_family_kernels.hpp"
#include "decode_kernels.hpp"
#include "phase_math.hpp"

#include <cstdint>

namespace fpp::detail {

// Least residual gap (DN^2) between the two best orders, as a fraction of the
// full scale squared: 0.0013 is 85 DN^2 at 8 bits, about 25 times the noise
// variance of the effects rig's camera at mid grey (sigma 1.8 DN). On the
// DecodeFamilies plane a gap of 75 DN^2 still lets 2 aliases through, 90
// flags 1 % of the pixels.
inline constexpr float kMicroMinGap = 0.0013f;

struct MicroParams {
    int others = 0;   // F - 1
    float period = 0; // P_1
    float offset = 0; // phase_offset, rad
    float offset_fraction = 0;
    const double* periods = nullptr; // P_1 .. P_F
    int first_order = 0;
    int orders = 0;
    const float* order_cos = nullptr; // [f - 1][order]: cos(2 pi k P_1 / P_f)
    const float* order_sin = nullptr;
    float lowest = -1.5f; // candidates outside [lowest, highest] are not taken
    float highest = 0;
    float sign = 1;                       // -shift_sign weights are in cos_w / sin_w already
    const float* extra_offsets = nullptr; // per other period, rad (added to offset)
    float min_gap = 0;                    // kMicroMinGap * full scale^2, DN^2
    float min_modulation = 0;             // DN: below it a pixel is masked whatever its order
    bool every_order = false;             // DecodeOptions::micro_every_order
};

// Scratch floats per pixel that micro_search needs.
inline int micro_scratch_floats(int others) {
    return 3 * others + 2;
}

// Pass 1: A, B, wrapped fraction of the first period (into fraction,
// modulation, mean), and per other period the measured cosine (I - A) / B and
// cos / sin of 2 pi frac_1 P_1 / P_f + offset, into scratch rows of `stride`.
template <class T>
FPP_KERNEL void micro_base_row(const T* const* in, int n, const float* cw, const float* sw,
                               const MicroParams& m, float* __restrict fraction,
                               float* __restrict modulation, float* __restrict mean,
                               float* __restrict scratch, int stride) {
    const T* __restrict i0 = in[0];
    const T* __restrict i1 = in[1];
    const T* __restrict i2 = in[2];
    for (int x = 0; x < n; ++x) {
        const float v0 = static_cast<float>(i0[x]);
        const float v1 = static_cast<float>(i1[x]);
        const float v2 = static_cast<float>(i2[x]);
        const float cc = v0 * cw[0] + v1 * cw[1] + v2 * cw[2];
        const float ss = v0 * sw[0] + v1 * sw[1] + v2 * sw[2];
        fraction[x] = wrapped_fraction(cc, ss, m.offset_fraction);
        modulation[x] = (2.0f / 3.0f) * sqrt_fast(cc * cc + ss * ss);
        mean[x] = (v0 + v1 + v2) * (1.0f / 3.0f);
    }
    for (int f = 0; f < m.others; ++f) {
        const T* __restrict v = in[3 + f];
        float* __restrict measured =
            scratch + static_cast<std::size_t>(3 * f) * std::size_t(stride);
        float* __restrict ca = measured + stride;
        float* __restrict sa = ca + stride;
        const float ratio = 2.0f * kPi * static_cast<float>(m.periods[0] / m.periods[f + 1]);
        const float extra = m.offset + (m.extra_offsets != nullptr ? m.extra_offsets[f] : 0.0f);
        for (int x = 0; x < n; ++x) {
            const float b = modulation[x];
            measured[x] = (static_cast<float>(v[x]) - mean[x]) / (b > 1e-3f ? b : 1e-3f);
            float s, c;
            sincos_fast(fraction[x] * ratio + extra, s, c);
            ca[x] = c;
            sa[x] = s;
        }
    }
}

// Pass 2: the best candidate per pixel; writes the projector coordinate (px)
// into `fraction` and 1 into `ambiguous` where it is not clearly the best.
void micro_search(int n, const MicroParams& m, float* fraction, const float* modulation,
                  std::uint8_t* ambiguous, float* scratch, int stride);

} // namespace fpp::detail
