#pragma once
// Per-pixel kernels of the decoding steps. Each processes a contiguous run of
// pixels (a span of the image, which may cross rows: no kernel looks at a
// neighbour) and is written as a simple loop over contiguous arrays that GCC
// vectorises at -O3. `first` means "assign instead of accumulate", so no
// buffer ever needs clearing and the order of operations per pixel is fixed by
// the plan alone.
//
// T is the frame's sample type (8- or 16-bit). Gray thresholds are stored in
// the same type as the samples they are compared with, so the comparisons run
// on 16 or 32 lanes per vector instead of being widened to 32 bits.

#include "decode_weights.hpp"
#include "phase_math.hpp"

#include <cstdint>
#include <type_traits>

namespace fpp::detail {

// sat |= bits where the sample is at or above `level` (assigns when `first`).
template <class T>
FPP_KERNEL void saturation_row(const T* in, int n, T level, std::uint8_t bits, bool first,
                               std::uint8_t* sat) {
    if (first) {
        for (int x = 0; x < n; ++x)
            sat[x] = in[x] >= level ? bits : std::uint8_t{0};
    } else {
        for (int x = 0; x < n; ++x)
            sat[x] = static_cast<std::uint8_t>(sat[x] | (in[x] >= level ? bits : std::uint8_t{0}));
    }
}

// How a kernel that reads phase frames updates the saturation bytes.
struct SatUpdate {
    std::uint8_t* sat = nullptr;
    std::uint8_t bits = 0;    // axis bits of the frames read
    std::uint8_t keep = 0xff; // 0 when this is the first write (assign), else 0xff (OR)
};

// Sums of a phase block over its N frames: c = sum I cos(delta_k),
// s = sum I (-shift_sign sin(delta_k)), a = sum I; also ORs `sat.bits` into
// the saturation bytes where any sample reaches `level`. Two forms, chosen by
// N alone so that every decoding path of a block uses the same one:
//  - phase_block_classes (N <= kMaxClassSteps): integer sums per weight class
//    (decode_weights.hpp), then one multiply per class;
//  - phase_frames_pass (larger N): frame after frame in order k = 0 .. N-1,
//    G frames per pass with the sums in registers; the per-pixel operations
//    and their order do not depend on G.

// Integer class sums of frames K.. of the block, and the running maximum for
// the saturation test, for one pixel.
template <class T, class Acc, int N, int K>
FPP_KERNEL void add_class_samples(const T* const* in, int x, Acc* cos_sum, Acc* sin_sum, Acc& sum,
                                  T& peak) {
    const T v = in[K][x];
    peak = peak > v ? peak : v;
    constexpr WeightClass c = cos_class(N, K);
    constexpr WeightClass s = sin_class(N, K);
    if constexpr (c.sign > 0)
        cos_sum[c.index] = static_cast<Acc>(cos_sum[c.index] + v);
    else if constexpr (c.sign < 0)
        cos_sum[c.index] = static_cast<Acc>(cos_sum[c.index] - v);
    if constexpr (s.sign > 0)
        sin_sum[s.index] = static_cast<Acc>(sin_sum[s.index] + v);
    else if constexpr (s.sign < 0)
        sin_sum[s.index] = static_cast<Acc>(sin_sum[s.index] - v);
    sum = static_cast<Acc>(sum + v);
    if constexpr (K + 1 < N)
        add_class_samples<T, Acc, N, K + 1>(in, x, cos_sum, sin_sum, sum, peak);
}

template <class T, int N>
FPP_KERNEL void phase_block_classes(const T* const* in, int n, const float* class_cos_w,
                                    const float* class_sin_w, T level, const SatUpdate& sat,
                                    float* __restrict c, float* __restrict s, float* __restrict a) {
    static_assert(N >= 3 && N <= kMaxClassSteps);
    // 16-bit lanes for 8-bit samples: |sums| <= 16 * 255.
    using Acc = std::conditional_t<sizeof(T) == 1, std::int16_t, std::int32_t>;
    constexpr int kCos = cos_class_count(N);
    constexpr int kSin = sin_class_count(N);
    const T* p[N];
    for (int k = 0; k < N; ++k)
        p[k] = in[k];
    float wc[kCos], ws[kSin];
    for (int j = 0; j < kCos; ++j)
        wc[j] = class_cos_w[j];
    for (int j = 0; j < kSin; ++j)
        ws[j] = class_sin_w[j];
    std::uint8_t* __restrict sat_out = sat.sat;
    const std::uint8_t bits = sat.bits;
    const std::uint8_t keep = sat.keep;
    for (int x = 0; x < n; ++x) {
        Acc cos_sum[kCos] = {};
        Acc sin_sum[kSin] = {};
        Acc sum = 0;
        T peak = 0;
        add_class_samples<T, Acc, N, 0>(p, x, cos_sum, sin_sum, sum, peak);
        sat_out[x] = static_cast<std::uint8_t>((sat_out[x] & keep) | (peak >= level ? bits : 0));
        // Class sums below 2^24 convert to float exactly.
        float cc = wc[0] * static_cast<float>(static_cast<std::int32_t>(cos_sum[0]));
        for (int j = 1; j < kCos; ++j)
            cc += wc[j] * static_cast<float>(static_cast<std::int32_t>(cos_sum[j]));
        float ss = ws[0] * static_cast<float>(static_cast<std::int32_t>(sin_sum[0]));
        for (int j = 1; j < kSin; ++j)
            ss += ws[j] * static_cast<float>(static_cast<std::int32_t>(sin_sum[j]));
        c[x] = cc;
        s[x] = ss;
        a[x] = static_cast<float>(static_cast<std::int32_t>(sum));
    }
}

// G consecutive frames k..k+G-1 (G <= 4) of a block of more than
// kMaxClassSteps steps: c += I cos(delta_k), s += I (-shift_sign sin(delta_k)),
// a += I; the block's first frame assigns.
template <class T, int G, bool First>
FPP_KERNEL void phase_frames_pass(const T* const* in, int n, const float* cw, const float* sw,
                                  T level, const SatUpdate& sat, float* __restrict c,
                                  float* __restrict s, float* __restrict a) {
    static_assert(G >= 1 && G <= 4);
    // Distinct restrict pointers: otherwise GCC gives up on the alias checks.
    const T* __restrict i0 = in[0];
    const T* __restrict i1 = in[G > 1 ? 1 : 0];
    const T* __restrict i2 = in[G > 2 ? 2 : 0];
    const T* __restrict i3 = in[G > 3 ? 3 : 0];
    std::uint8_t* __restrict sat_out = sat.sat;
    const std::uint8_t bits = sat.bits;
    const std::uint8_t keep = sat.keep;
    const float c0 = cw[0], c1 = cw[G > 1 ? 1 : 0], c2 = cw[G > 2 ? 2 : 0], c3 = cw[G > 3 ? 3 : 0];
    const float s0 = sw[0], s1 = sw[G > 1 ? 1 : 0], s2 = sw[G > 2 ? 2 : 0], s3 = sw[G > 3 ? 3 : 0];
    for (int x = 0; x < n; ++x) {
        T m = i0[x];
        if constexpr (G > 1)
            m = m > i1[x] ? m : i1[x];
        if constexpr (G > 2)
            m = m > i2[x] ? m : i2[x];
        if constexpr (G > 3)
            m = m > i3[x] ? m : i3[x];
        sat_out[x] = static_cast<std::uint8_t>((sat_out[x] & keep) | (m >= level ? bits : 0));
        const float v0 = static_cast<float>(i0[x]);
        float cc, ss, aa;
        if constexpr (First) {
            cc = v0 * c0;
            ss = v0 * s0;
            aa = v0;
        } else {
            cc = c[x] + v0 * c0;
            ss = s[x] + v0 * s0;
            aa = a[x] + v0;
        }
        if constexpr (G > 1) {
            const float v1 = static_cast<float>(i1[x]);
            cc += v1 * c1;
            ss += v1 * s1;
            aa += v1;
        }
        if constexpr (G > 2) {
            const float v2 = static_cast<float>(i2[x]);
            cc += v2 * c2;
            ss += v2 * s2;
            aa += v2;
        }
        if constexpr (G > 3) {
            const float v3 = static_cast<float>(i3[x]);
            cc += v3 * c3;
            ss += v3 * s3;
            aa += v3;
        }
        c[x] = cc;
        s[x] = ss;
        a[x] = aa;
    }
}

// One loop per case of `first`: a loop-invariant ?: on loads inside the loop
// keeps GCC from vectorising it.
template <class T, int G>
FPP_KERNEL void phase_frames_row(const T* const* in, int n, const float* cw, const float* sw,
                                 bool first, T level, const SatUpdate& sat, float* c, float* s,
                                 float* a) {
    if (first)
        phase_frames_pass<T, G, true>(in, n, cw, sw, level, sat, c, s, a);
    else
        phase_frames_pass<T, G, false>(in, n, cw, sw, level, sat, c, s, a);
}

// Wrapped fraction of a period in [0, 1) from the sums, the phase offset
// removed: (theta - offset) / (2 pi) mod 1.
FPP_KERNEL float wrapped_fraction(float c, float s, float offset_fraction) {
    float f = atan2_fast(s, c) * kInvTwoPi - offset_fraction;
    f -= floor_fast(f);
    return select(f < 1.0f, f, 0.0f); // rounding may land exactly on 1
}

// In place: c -> wrapped fraction (wrapped_fraction); s -> modulation
// B = (2/N)|sum|; a -> mean A = sum / N. With a `threshold` (gray or
// centerline thresholded against the mean), also stores floor(A) in the sample
// type, so that for integer samples I > floor(A) is exactly I > A.
template <class T>
FPP_KERNEL void phase_finish_row(int n, float two_over_n, float one_over_n, float offset_fraction,
                                 float* __restrict c, float* __restrict s, float* __restrict a,
                                 T* __restrict threshold) {
    constexpr float top = static_cast<float>(static_cast<T>(~T{0}));
    if (threshold == nullptr) {
        for (int x = 0; x < n; ++x) {
            const float cc = c[x];
            const float ss = s[x];
            c[x] = wrapped_fraction(cc, ss, offset_fraction);
            s[x] = two_over_n * sqrt_fast(cc * cc + ss * ss);
            a[x] *= one_over_n;
        }
    } else {
        for (int x = 0; x < n; ++x) {
            const float cc = c[x];
            const float ss = s[x];
            c[x] = wrapped_fraction(cc, ss, offset_fraction);
            s[x] = two_over_n * sqrt_fast(cc * cc + ss * ss);
            const float mean = a[x] * one_over_n;
            a[x] = mean;
            threshold[x] = static_cast<T>(static_cast<std::int32_t>(mean < top ? mean : top));
        }
    }
}

// Gray threshold from white and black: floor((W + B) / 2), in the sample type.
// I > floor((W + B)/2) is exactly 2 I > W + B for integers.
template <class T> FPP_KERNEL void white_black_row(const T* in, int n, bool first, T* threshold) {
    if (first) {
        for (int x = 0; x < n; ++x)
            threshold[x] = in[x];
    } else {
        for (int x = 0; x < n; ++x)
            threshold[x] = static_cast<T>(
                (static_cast<std::uint32_t>(threshold[x]) + static_cast<std::uint32_t>(in[x])) >>
                1);
    }
}

// G consecutive planes of one gray block against one threshold (white/black or
// phase mean): code |= bits[k] where I_k > threshold. Same result however the
// planes are grouped (G = 1 in streaming).
template <class T, int G>
FPP_KERNEL void gray_planes_row(const T* const* in, int n, const T* __restrict threshold,
                                const std::uint16_t* bits, bool first,
                                std::uint16_t* __restrict code) {
    static_assert(G >= 1 && G <= 4);
    const T* __restrict i0 = in[0];
    const T* __restrict i1 = in[G > 1 ? 1 : 0];
    const T* __restrict i2 = in[G > 2 ? 2 : 0];
    const T* __restrict i3 = in[G > 3 ? 3 : 0];
    const std::uint16_t b0 = bits[0], b1 = bits[G > 1 ? 1 : 0], b2 = bits[G > 2 ? 2 : 0],
                        b3 = bits[G > 3 ? 3 : 0];
    const std::uint16_t zero = 0;
    for (int x = 0; x < n; ++x) {
        const T t = threshold[x];
        auto c = static_cast<std::uint16_t>((first ? zero : code[x]) | (i0[x] > t ? b0 : zero));
        if constexpr (G > 1)
            c = static_cast<std::uint16_t>(c | (i1[x] > t ? b1 : zero));
        if constexpr (G > 2)
            c = static_cast<std::uint16_t>(c | (i2[x] > t ? b2 : zero));
        if constexpr (G > 3)
            c = static_cast<std::uint16_t>(c | (i3[x] > t ? b3 : zero));
        code[x] = c;
    }
}

// code |= bit where the plane is brighter than its inverse.
template <class T>
FPP_KERNEL void gray_inverse_row(const T* in, const T* inverse, int n, std::uint16_t bit,
                                 bool first, std::uint16_t* code) {
    if (first) {
        for (int x = 0; x < n; ++x)
            code[x] = in[x] > inverse[x] ? bit : std::uint16_t{0};
    } else {
        for (int x = 0; x < n; ++x)
            code[x] = static_cast<std::uint16_t>(code[x] | (in[x] > inverse[x] ? bit : 0u));
    }
}

// line = 1 where the centerline frame is brighter than the phase mean
// (threshold = floor(A), see phase_finish_row).
template <class T>
FPP_KERNEL void centerline_row(const T* in, int n, const T* threshold, std::uint8_t* line) {
    for (int x = 0; x < n; ++x)
        line[x] = in[x] > threshold[x] ? std::uint8_t{1} : std::uint8_t{0};
}

} // namespace fpp::detail
