#pragma once
// Per-row kernels applied as frames arrive. Each processes one full camera row
// and is written as a simple loop over contiguous arrays that GCC vectorises at
// -O3. `first` means "assign instead of accumulate", so no buffer ever needs
// clearing and the order of operations per pixel is fixed by the plan alone.

#include "phase_math.hpp"

#include <cstdint>

namespace fpp::detail {

// sat |= bits where the sample is at or above `level`.
template <class T>
FPP_KERNEL void saturation_row(const T* in, int n, T level, std::uint8_t bits, bool first, std::uint8_t* sat) {
    if (first) {
        for (int x = 0; x < n; ++x) sat[x] = in[x] >= level ? bits : std::uint8_t{0};
    } else {
        for (int x = 0; x < n; ++x)
            sat[x] = static_cast<std::uint8_t>(sat[x] | (in[x] >= level ? bits : std::uint8_t{0}));
    }
}

// Phase sums: c += I cos(delta_k), s += I (-shift_sign sin(delta_k)), a += I.
template <class T>
FPP_KERNEL void phase_frame_row(const T* in, int n, float cw, float sw, bool first, float* c, float* s,
                     float* a) {
    if (first) {
        for (int x = 0; x < n; ++x) {
            const float v = static_cast<float>(in[x]);
            c[x] = v * cw;
            s[x] = v * sw;
            a[x] = v;
        }
    } else {
        for (int x = 0; x < n; ++x) {
            const float v = static_cast<float>(in[x]);
            c[x] += v * cw;
            s[x] += v * sw;
            a[x] += v;
        }
    }
}

// G consecutive frames of one block in one pass (batch mode: all frames at
// hand). Per pixel the same operations in the same order as G calls of
// phase_frame_row, so the sums are bit-identical; only the accumulators stay
// in registers between frames.
template <class T, int G>
FPP_KERNEL void phase_frames_row(const T* const* in, int n, const float* cw, const float* sw,
                                 bool first, float* __restrict c, float* __restrict s,
                                 float* __restrict a) {
    static_assert(G >= 2 && G <= 4);
    // Distinct restrict pointers: otherwise GCC gives up on the alias checks.
    const T* __restrict i0 = in[0];
    const T* __restrict i1 = in[1];
    const T* __restrict i2 = in[G > 2 ? 2 : 1];
    const T* __restrict i3 = in[G > 3 ? 3 : 1];
    const float c0 = cw[0], c1 = cw[1], c2 = cw[G > 2 ? 2 : 1], c3 = cw[G > 3 ? 3 : 1];
    const float s0 = sw[0], s1 = sw[1], s2 = sw[G > 2 ? 2 : 1], s3 = sw[G > 3 ? 3 : 1];
    for (int x = 0; x < n; ++x) {
        const float v0 = static_cast<float>(i0[x]);
        // First frame: v * w (as phase_frame_row assigns); else c + v * w.
        float cc = first ? v0 * c0 : c[x] + v0 * c0;
        float ss = first ? v0 * s0 : s[x] + v0 * s0;
        float aa = first ? v0 : a[x] + v0;
        const float v1 = static_cast<float>(i1[x]);
        cc += v1 * c1;
        ss += v1 * s1;
        aa += v1;
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

// In place: c -> wrapped fraction of a period in [0, 1) with the phase offset
// removed, (theta - offset) / (2 pi) mod 1; s -> modulation B = (2/N)|sum|;
// a -> mean A = sum / N.
FPP_KERNEL void phase_finish_row(int n, float two_over_n, float one_over_n, float offset_fraction,
                             float* c, float* s, float* a) {
    for (int x = 0; x < n; ++x) {
        const float cc = c[x];
        const float ss = s[x];
        float f = atan2_fast(ss, cc) * kInvTwoPi - offset_fraction;
        f -= floor_fast(f);
        c[x] = select(f < 1.0f, f, 0.0f); // rounding may land exactly on 1
        s[x] = two_over_n * sqrt_fast(cc * cc + ss * ss);
        a[x] *= one_over_n;
    }
}

// Gray threshold from white and black: floor((W + B) / 2), stored in 16 bits.
// I > floor((W + B)/2) is exactly 2 I > W + B for integers, and comparing in
// the frame's own integer type avoids float conversions.
template <class T> FPP_KERNEL void white_black_row(const T* in, int n, bool first, std::uint16_t* threshold) {
    if (first) {
        for (int x = 0; x < n; ++x) threshold[x] = in[x];
    } else {
        for (int x = 0; x < n; ++x)
            threshold[x] = static_cast<std::uint16_t>(
                (static_cast<std::uint32_t>(threshold[x]) + static_cast<std::uint32_t>(in[x])) >> 1);
    }
}

// Integer gray threshold from a phase mean: floor(A), so that for integer
// samples I > floor(A) is exactly I > A.
FPP_KERNEL void mean_threshold_row(const float* mean, int n, std::uint16_t* threshold) {
    for (int x = 0; x < n; ++x) {
        const float a = mean[x] < 65535.0f ? mean[x] : 65535.0f;
        threshold[x] = static_cast<std::uint16_t>(static_cast<std::int32_t>(a));
    }
}

// code |= bit where I > threshold (white/black or phase-mean threshold).
template <class T>
FPP_KERNEL void gray_threshold_row(const T* in, int n, const std::uint16_t* threshold, std::uint16_t bit,
                        bool first, std::uint16_t* code) {
    if (first) {
        for (int x = 0; x < n; ++x) code[x] = in[x] > threshold[x] ? bit : std::uint16_t{0};
    } else {
        for (int x = 0; x < n; ++x)
            code[x] = static_cast<std::uint16_t>(code[x] | (in[x] > threshold[x] ? bit : 0u));
    }
}

// G consecutive gray planes against one threshold in one pass (batch mode),
// same result as G calls of gray_threshold_row.
template <class T, int G>
FPP_KERNEL void gray_planes_row(const T* const* in, int n, const std::uint16_t* threshold,
                     const std::uint16_t* bits, bool first, std::uint16_t* code) {
    for (int x = 0; x < n; ++x) {
        const std::uint16_t t = threshold[x];
        std::uint32_t c = first ? 0u : code[x];
        for (int k = 0; k < G; ++k) c |= in[k][x] > t ? bits[k] : 0u;
        code[x] = static_cast<std::uint16_t>(c);
    }
}

// code |= bit where the plane is brighter than its inverse.
template <class T>
FPP_KERNEL void gray_inverse_row(const T* in, const T* inverse, int n, std::uint16_t bit, bool first,
                      std::uint16_t* code) {
    if (first) {
        for (int x = 0; x < n; ++x) code[x] = in[x] > inverse[x] ? bit : std::uint16_t{0};
    } else {
        for (int x = 0; x < n; ++x)
            code[x] = static_cast<std::uint16_t>(code[x] | (in[x] > inverse[x] ? bit : 0u));
    }
}

// line = 1 where the centerline frame is brighter than the phase mean
// (threshold = floor(A), see mean_threshold_row).
template <class T>
FPP_KERNEL void centerline_row(const T* in, int n, const std::uint16_t* threshold, std::uint8_t* line) {
    for (int x = 0; x < n; ++x) line[x] = in[x] > threshold[x] ? std::uint8_t{1} : std::uint8_t{0};
}

} // namespace fpp::detail
