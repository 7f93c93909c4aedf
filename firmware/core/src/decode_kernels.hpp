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
void saturation_row(const T* in, int n, T level, std::uint8_t bits, bool first, std::uint8_t* sat) {
    if (first) {
        for (int x = 0; x < n; ++x) sat[x] = in[x] >= level ? bits : std::uint8_t{0};
    } else {
        for (int x = 0; x < n; ++x)
            sat[x] = static_cast<std::uint8_t>(sat[x] | (in[x] >= level ? bits : std::uint8_t{0}));
    }
}

// Phase sums: c += I cos(delta_k), s += I (-shift_sign sin(delta_k)), a += I.
template <class T>
void phase_frame_row(const T* in, int n, float cw, float sw, bool first, float* c, float* s,
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

// In place: c -> wrapped fraction of a period in [0, 1) with the phase offset
// removed, (theta - offset) / (2 pi) mod 1; s -> modulation B = (2/N)|sum|;
// a -> mean A = sum / N.
inline void phase_finish_row(int n, float two_over_n, float one_over_n, float offset_fraction,
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
template <class T> void white_black_row(const T* in, int n, bool first, std::uint16_t* threshold) {
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
inline void mean_threshold_row(const float* mean, int n, std::uint16_t* threshold) {
    for (int x = 0; x < n; ++x) {
        const float a = mean[x] < 65535.0f ? mean[x] : 65535.0f;
        threshold[x] = static_cast<std::uint16_t>(static_cast<std::int32_t>(a));
    }
}

// code |= bit where I > threshold (white/black or phase-mean threshold).
template <class T>
void gray_threshold_row(const T* in, int n, const std::uint16_t* threshold, std::uint16_t bit,
                        bool first, std::uint16_t* code) {
    if (first) {
        for (int x = 0; x < n; ++x) code[x] = in[x] > threshold[x] ? bit : std::uint16_t{0};
    } else {
        for (int x = 0; x < n; ++x)
            code[x] = static_cast<std::uint16_t>(code[x] | (in[x] > threshold[x] ? bit : 0u));
    }
}

// code |= bit where the plane is brighter than its inverse.
template <class T>
void gray_inverse_row(const T* in, const T* inverse, int n, std::uint16_t bit, bool first,
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
void centerline_row(const T* in, int n, const std::uint16_t* threshold, std::uint8_t* line) {
    for (int x = 0; x < n; ++x) line[x] = in[x] > threshold[x] ? std::uint8_t{1} : std::uint8_t{0};
}

} // namespace fpp::detail
