#pragma once
// Per-pixel kernels of the fpp-capture/2 families (decode_kernels.hpp has the
// standard ones): 2+1 and modulated phase shifting, micro phase shifting,
// n-ary code digits and the white/black levels of code-only axes. Same rules:
// loops over contiguous spans, no neighbour, `first` assigns.

#include "decode_kernels.hpp"
#include "phase_math.hpp"

#include <cstdint>
#include <type_traits>

namespace fpp::detail {

// sin and cos of x (|x| < 2^20 rad) to about 1e-7: reduced to [-pi, pi] by
// whole turns, then to [-pi/2, pi/2] (sin(pi - r) = sin r, cos(pi - r) =
// -cos r), then Taylor polynomials (degree 11 and 12: error below 6e-8 there).
FPP_KERNEL void sincos_fast(float x, float& s, float& c) {
    constexpr float kTwoPiHi = 6.28318548f;
    constexpr float kTwoPiLo = -1.74845553e-07f; // 2 pi - kTwoPiHi
    const float turns = round_nearest(x * kInvTwoPi);
    float r = x - turns * kTwoPiHi;
    r -= turns * kTwoPiLo;
    const bool fold = abs_fast(r) > kHalfPi;
    r = select(fold, __builtin_copysignf(kPi, r) - r, r);
    const float u = r * r;
    float sp = -2.50521084e-08f;
    sp = sp * u + 2.75573192e-06f;
    sp = sp * u - 1.98412698e-04f;
    sp = sp * u + 8.33333333e-03f;
    sp = sp * u - 1.66666667e-01f;
    s = r + r * u * sp;
    float cp = 2.08767570e-09f;
    cp = cp * u - 2.75573192e-07f;
    cp = cp * u + 2.48015873e-05f;
    cp = cp * u - 1.38888889e-03f;
    cp = cp * u + 4.16666667e-02f;
    cp = cp * u - 0.5f;
    const float cr = 1.0f + u * cp;
    c = select(fold, -cr, cr);
}

// 2+1 phase shifting (frames sin, cos, flat): c = I1 - I2 = B cos(phi),
// s = shift_sign (I0 - I2) = B sin(phi), a = I2 = A. Finished with
// phase_finish_row(two_over_n = 1, one_over_n = 1).
template <class T>
FPP_KERNEL void two_plus_one_row(const T* __restrict i0, const T* __restrict i1,
                                 const T* __restrict i2, int n, float sign, T level,
                                 const SatUpdate& sat, float* __restrict c, float* __restrict s,
                                 float* __restrict a) {
    std::uint8_t* __restrict sat_out = sat.sat;
    for (int x = 0; x < n; ++x) {
        T peak = i0[x] > i1[x] ? i0[x] : i1[x];
        peak = peak > i2[x] ? peak : i2[x];
        sat_out[x] =
            static_cast<std::uint8_t>((sat_out[x] & sat.keep) | (peak >= level ? sat.bits : 0));
        const float flat = static_cast<float>(i2[x]);
        c[x] = static_cast<float>(i1[x]) - flat;
        s[x] = sign * (static_cast<float>(i0[x]) - flat);
        a[x] = flat;
    }
}

// One carrier shift j of shift i of a modulated block: the carrier sums
// cr (+)= I cos(2 pi j / M), sr (+)= I sin(2 pi j / M) and the raw sum.
template <class T>
FPP_KERNEL void carrier_frame_row(const T* __restrict in, int n, float wc, float ws, bool first,
                                  bool raw_first, float* __restrict cr, float* __restrict sr,
                                  float* __restrict raw) {
    for (int x = 0; x < n; ++x) {
        const float v = static_cast<float>(in[x]);
        cr[x] = first ? v * wc : cr[x] + v * wc;
        sr[x] = first ? v * ws : sr[x] + v * ws;
        raw[x] = raw_first ? v : raw[x] + v;
    }
}

// The carrier amplitude D_i = (2/M) |sum_j I_ij e^{-i 2 pi j / M}| of shift i,
// added into the standard N-step sums with the shift's weights.
FPP_KERNEL void carrier_amplitude_row(int n, float two_over_m, float wc, float ws, bool first,
                                      const float* __restrict cr, const float* __restrict sr,
                                      float* __restrict c, float* __restrict s,
                                      float* __restrict a) {
    for (int x = 0; x < n; ++x) {
        const float d = two_over_m * sqrt_fast(cr[x] * cr[x] + sr[x] * sr[x]);
        c[x] = first ? d * wc : c[x] + d * wc;
        s[x] = first ? d * ws : s[x] + d * ws;
        a[x] = first ? d : a[x] + d;
    }
}

// The M carrier frames of one shift of a modulated block in one pass (M = 3
// or 4, the carrier sums in registers): the same per-pixel operations, in the
// same order, as carrier_frame_row over its frames then carrier_amplitude_row,
// and the saturation test of its frames. `First`: the block's first shift.
template <class T, int M, bool First>
FPP_KERNEL void modulated_shift_pass(const T* const* in, int n, const float* carrier_cos,
                                     const float* carrier_sin, float two_over_m, float wc, float ws,
                                     T level, const SatUpdate& sat, float* __restrict c,
                                     float* __restrict s, float* __restrict a,
                                     float* __restrict raw) {
    static_assert(M == 3 || M == 4);
    const T* __restrict i0 = in[0];
    const T* __restrict i1 = in[1];
    const T* __restrict i2 = in[2];
    const T* __restrict i3 = in[M > 3 ? 3 : 2];
    const float c0 = carrier_cos[0], c1 = carrier_cos[1], c2 = carrier_cos[2];
    const float s0 = carrier_sin[0], s1 = carrier_sin[1], s2 = carrier_sin[2];
    const float c3 = carrier_cos[M > 3 ? 3 : 2], s3 = carrier_sin[M > 3 ? 3 : 2];
    std::uint8_t* __restrict sat_out = sat.sat;
    const std::uint8_t bits = sat.bits;
    const std::uint8_t keep = sat.keep;
    for (int x = 0; x < n; ++x) {
        T peak = i0[x] > i1[x] ? i0[x] : i1[x];
        peak = peak > i2[x] ? peak : i2[x];
        if constexpr (M > 3)
            peak = peak > i3[x] ? peak : i3[x];
        sat_out[x] = static_cast<std::uint8_t>((sat_out[x] & keep) | (peak >= level ? bits : 0));
        const float v0 = static_cast<float>(i0[x]);
        const float v1 = static_cast<float>(i1[x]);
        const float v2 = static_cast<float>(i2[x]);
        float cr = v0 * c0;
        float sr = v0 * s0;
        float sum = First ? v0 : raw[x] + v0;
        cr = cr + v1 * c1;
        sr = sr + v1 * s1;
        sum = sum + v1;
        cr = cr + v2 * c2;
        sr = sr + v2 * s2;
        sum = sum + v2;
        if constexpr (M > 3) {
            const float v3 = static_cast<float>(i3[x]);
            cr = cr + v3 * c3;
            sr = sr + v3 * s3;
            sum = sum + v3;
        }
        raw[x] = sum;
        const float d = two_over_m * sqrt_fast(cr * cr + sr * sr);
        if constexpr (First) {
            c[x] = d * wc;
            s[x] = d * ws;
            a[x] = d;
        } else {
            c[x] = c[x] + d * wc;
            s[x] = s[x] + d * ws;
            a[x] = a[x] + d;
        }
    }
}

template <class T, int M>
FPP_KERNEL void modulated_shift_row(const T* const* in, int n, const float* carrier_cos,
                                    const float* carrier_sin, float two_over_m, float wc, float ws,
                                    bool first, T level, const SatUpdate& sat, float* c, float* s,
                                    float* a, float* raw) {
    if (first)
        modulated_shift_pass<T, M, true>(in, n, carrier_cos, carrier_sin, two_over_m, wc, ws, level,
                                         sat, c, s, a, raw);
    else
        modulated_shift_pass<T, M, false>(in, n, carrier_cos, carrier_sin, two_over_m, wc, ws,
                                          level, sat, c, s, a, raw);
}

// Gray threshold of a modulated block: the raw mean (ambient + R/4) plus the
// mean carrier amplitude (R/4) is ambient + R/2, the middle of black and
// white. In the sample type, floored like phase_finish_row's.
template <class T>
FPP_KERNEL void modulated_threshold_row(int n, float one_over_frames, const float* __restrict raw,
                                        const float* __restrict mean, T* __restrict threshold) {
    constexpr float top = static_cast<float>(static_cast<T>(~T{0}));
    for (int x = 0; x < n; ++x) {
        const float t = raw[x] * one_over_frames + mean[x];
        threshold[x] = static_cast<T>(static_cast<std::int32_t>(t < top ? t : top));
    }
}

// n-ary code plane: digit = round((I - black) / (white - black) (L - 1)),
// clamped to [0, L - 1]; code (+)= digit * weight.
template <class T>
FPP_KERNEL void gray_digit_row(const T* __restrict in, const T* __restrict white,
                               const T* __restrict black, int n, float top_digit,
                               std::uint16_t weight, bool first, std::uint16_t* __restrict code) {
    const float w = static_cast<float>(weight);
    for (int x = 0; x < n; ++x) {
        const float b = static_cast<float>(black[x]);
        float range = static_cast<float>(white[x]) - b;
        range = range > 1.0f ? range : 1.0f;
        float d = round_nearest((static_cast<float>(in[x]) - b) * top_digit / range);
        d = d < 0.0f ? 0.0f : d;
        d = d > top_digit ? top_digit : d;
        const float before = first ? 0.0f : static_cast<float>(code[x]);
        code[x] = static_cast<std::uint16_t>(static_cast<std::int32_t>(before + d * w));
    }
}

// n-ary code plane scaled by the phase block it indexes: its fringes span
// the projector's 0 .. 1 as the code's levels do, so black is A - B and
// white A + B: digit = round((I - A + B) / (2 B) (L - 1)), clamped.
template <class T>
FPP_KERNEL void gray_digit_from_phase_row(const T* __restrict in, const float* __restrict mean,
                                          const float* __restrict modulation, int n,
                                          float top_digit, std::uint16_t weight, bool first,
                                          std::uint16_t* __restrict code) {
    const float w = static_cast<float>(weight);
    for (int x = 0; x < n; ++x) {
        float range = 2.0f * modulation[x];
        range = range > 1.0f ? range : 1.0f;
        float d =
            round_nearest((static_cast<float>(in[x]) - mean[x] + 0.5f * range) * top_digit / range);
        d = d < 0.0f ? 0.0f : d;
        d = d > top_digit ? top_digit : d;
        const float before = first ? 0.0f : static_cast<float>(code[x]);
        code[x] = static_cast<std::uint16_t>(static_cast<std::int32_t>(before + d * w));
    }
}

// Copy of a white or black frame (level planes, sample type).
template <class T> FPP_KERNEL void copy_row(const T* __restrict in, int n, T* __restrict out) {
    for (int x = 0; x < n; ++x)
        out[x] = in[x];
}

// Code-only axis thresholded by white and black: modulation (W - B) / 2 and
// mean (W + B) / 2, DN.
template <class T>
FPP_KERNEL void code_levels_row(const T* __restrict white, const T* __restrict black, int n,
                                float* __restrict modulation, float* __restrict mean) {
    for (int x = 0; x < n; ++x) {
        const float w = static_cast<float>(white[x]);
        const float b = static_cast<float>(black[x]);
        modulation[x] = 0.5f * (w - b);
        mean[x] = 0.5f * (w + b);
    }
}

// Signed lanes wide enough for a difference of two samples: 16 bits for
// 8-bit samples (twice the lanes per vector of 32), else 32; a bound on such
// a difference saturates at kWideMax.
template <class T>
using SignedWide = std::conditional_t<sizeof(T) == 1, std::int16_t, std::int32_t>;
template <class T> inline constexpr std::int32_t kWideMax = sizeof(T) == 1 ? 32767 : 2147483647;

// One plane of a code-only axis with inverse frames, in one pass:
// code |= bit where I > I_inv; doubt |= flag where |I - I_inv| < `margin2`
// (integer DN: 2 x the modulation floor, rounded up, since |I - I_inv| < x
// is |I - I_inv| < ceil(x) for integers); modulation = the largest half
// difference |I - I_inv| / 2 over the planes and mean = (I + I_inv) / 2 of
// the first plane, DN.
template <class T, bool First>
FPP_KERNEL void code_inverse_plane_pass(const T* __restrict in, const T* __restrict inverse, int n,
                                        std::uint16_t bit, std::int32_t margin2, std::uint16_t flag,
                                        std::uint16_t* __restrict code,
                                        std::uint16_t* __restrict doubt,
                                        float* __restrict modulation, float* __restrict mean) {
    for (int x = 0; x < n; ++x) {
        const std::int32_t i = in[x];
        const std::int32_t v = inverse[x];
        const std::int32_t diff = i > v ? i - v : v - i;
        const auto b = static_cast<std::uint16_t>(i > v ? bit : 0u);
        const auto d = static_cast<std::uint16_t>(diff < margin2 ? flag : 0u);
        const float half = 0.5f * static_cast<float>(diff);
        if constexpr (First) {
            code[x] = b;
            doubt[x] = d;
            modulation[x] = half;
            mean[x] = 0.5f * static_cast<float>(i + v);
        } else {
            code[x] = static_cast<std::uint16_t>(code[x] | b);
            doubt[x] = static_cast<std::uint16_t>(doubt[x] | d);
            const float before = modulation[x];
            modulation[x] = half > before ? half : before;
        }
    }
}

template <class T>
FPP_KERNEL void code_inverse_plane_row(const T* in, const T* inverse, int n, std::uint16_t bit,
                                       std::int32_t margin2, std::uint16_t flag, bool first,
                                       std::uint16_t* code, std::uint16_t* doubt, float* modulation,
                                       float* mean) {
    if (first)
        code_inverse_plane_pass<T, true>(in, inverse, n, bit, margin2, flag, code, doubt,
                                         modulation, mean);
    else
        code_inverse_plane_pass<T, false>(in, inverse, n, bit, margin2, flag, code, doubt,
                                          modulation, mean);
}

// Code-only planes: doubt |= `flag` (the plane's own bit) where the plane's
// sample lies within `margin` DN of its decision boundary (integer DN, the
// modulation floor rounded up: see code_inverse_plane_pass). Gray codes
// change one digit between neighbouring steps, so one doubtful plane is a
// code edge. Natural binary changes the digits 0..j at once at a carry edge
// (their planes share one edge profile, so all are doubtful together): with
// the planes' code weights as flags, unwrap_code_row recognises that
// pattern and resolves it. Any other two or more doubtful planes mean no
// contrast: low modulation.
template <class T>
FPP_KERNEL void doubt_threshold_row(const T* __restrict in, const T* __restrict threshold, int n,
                                    std::int32_t margin, std::uint16_t flag, bool first,
                                    std::uint16_t* __restrict doubt) {
    using Wide = SignedWide<T>;
    const auto bound = static_cast<Wide>(margin < kWideMax<T> ? margin : kWideMax<T>);
    for (int x = 0; x < n; ++x) {
        const auto i = static_cast<Wide>(in[x]);
        const auto t = static_cast<Wide>(threshold[x]);
        const auto d = static_cast<Wide>(i > t ? i - t : t - i);
        const auto near = static_cast<std::uint16_t>(d < bound ? flag : 0u);
        doubt[x] = static_cast<std::uint16_t>((first ? std::uint16_t{0} : doubt[x]) | near);
    }
}

// Natural binary against white and black (doubt_against_levels): a digit is
// also doubtful where its sample lies nearer the threshold than halfway to
// the white or black level, |I - threshold| < (W - B) / 4. Its finest planes
// (a 2-step period of 2.5 px at 10 bits over 1280 px) can be blurred to a
// few DN of contrast on either side of the threshold, which the absolute
// floor alone reads as confident digits.
template <class T>
FPP_KERNEL void doubt_levels_row(const T* __restrict in, const T* __restrict threshold,
                                 const T* __restrict white, const T* __restrict black, int n,
                                 std::int32_t margin, std::uint16_t flag, bool first,
                                 std::uint16_t* __restrict doubt) {
    // 8-bit samples: 16-bit lanes (|4 d| <= 1020).
    using Wide = SignedWide<T>;
    const auto bound = static_cast<Wide>(margin < kWideMax<T> ? margin : kWideMax<T>);
    for (int x = 0; x < n; ++x) {
        const auto i = static_cast<Wide>(in[x]);
        const auto t = static_cast<Wide>(threshold[x]);
        const auto d = static_cast<Wide>(i > t ? i - t : t - i);
        const auto range =
            static_cast<Wide>(static_cast<Wide>(white[x]) - static_cast<Wide>(black[x]));
        const auto near = static_cast<std::uint16_t>(
            ((d < bound) | (static_cast<Wide>(4 * d) < range)) ? flag : 0u);
        doubt[x] = static_cast<std::uint16_t>((first ? std::uint16_t{0} : doubt[x]) | near);
    }
}

// n-ary planes: the boundaries lie at (j + 1/2) (white - black) / (L - 1)
// above black.
template <class T>
FPP_KERNEL void doubt_digit_row(const T* __restrict in, const T* __restrict white,
                                const T* __restrict black, int n, float top_digit, float margin,
                                std::uint16_t flag, bool first, std::uint16_t* __restrict doubt) {
    for (int x = 0; x < n; ++x) {
        const float b = static_cast<float>(black[x]);
        float range = static_cast<float>(white[x]) - b;
        range = range > 1.0f ? range : 1.0f;
        const float scaled = (static_cast<float>(in[x]) - b) * top_digit / range;
        const float from_boundary = abs_fast(scaled - floor_fast(scaled) - 0.5f);
        const bool inside = (scaled > 0.0f) & (scaled < top_digit);
        const std::uint16_t near =
            (inside & (from_boundary * range < margin * top_digit)) ? flag : std::uint16_t{0};
        doubt[x] = static_cast<std::uint16_t>((first ? 0 : doubt[x]) | near);
    }
}

} // namespace fpp::detail
