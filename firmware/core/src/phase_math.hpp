#pragma once
// Scalar float functions written so that GCC vectorises the loops that use them
// (no calls into libm, no branches: comparisons become selects).

#include <bit>
#include <cstdint>

// Per-pixel kernels are plain C++ loops that GCC vectorises for the target's
// baseline (NEON on the AArch64 device). On x86-64 the baseline is SSE2, so
// the functions that hold these loops are also compiled for x86-64-v3 (AVX2)
// and x86-64-v4 (AVX-512) and picked at load time (the benchmark's full decode
// on two threads of its machine: 5.6 ms with SSE2, 3.2 ms with AVX2, 2.5 ms
// with AVX-512); elsewhere this expands to nothing. Every decoding path goes
// through the same functions, so batch and streaming results stay
// bit-identical on a given machine.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define FPP_VECTOR_CLONES                                                                          \
    __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define FPP_VECTOR_CLONES
#endif
// Files that hold kernel loops switch off floating-point contraction: GCC
// would otherwise fuse a * b + c into an FMA in some code shapes and not in
// others (a vectorised loop, its scalar tail, the batch mode's fused loop),
// and the batch and streaming forms must round identically.
#if defined(__GNUC__) && !defined(__clang__)
#define FPP_NO_FP_CONTRACT _Pragma("GCC optimize(\"fp-contract=off\")")
#else
#define FPP_NO_FP_CONTRACT _Pragma("clang fp contract(off)")
#endif

// Kernels and these functions are always inlined into their (cloned) callers, so a
// kernel is never compiled once for the baseline and called from an AVX2
// clone: the same arithmetic (FMA contraction included) everywhere.
#define FPP_KERNEL [[gnu::always_inline]] inline

namespace fpp::detail {

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kHalfPi = 1.57079632679489661923f;
inline constexpr float kQuarterPi = 0.78539816339744830962f;
inline constexpr float kInvTwoPi = 0.15915494309189533577f;

// c ? u : v by bit masks. With the default -ftrapping-math GCC sinks the
// arithmetic of a ?: arm into a branch and then cannot vectorise the loop;
// a bitwise select keeps both operands computed and the loop branch-free.
FPP_KERNEL float select(bool c, float u, float v) {
    const std::uint32_t m = 0u - static_cast<std::uint32_t>(c);
    return std::bit_cast<float>((std::bit_cast<std::uint32_t>(u) & m) |
                                (std::bit_cast<std::uint32_t>(v) & ~m));
}

// copysign(r, s) for r >= +0 (sign bit clear): one AND and one OR instead of
// clearing r's sign first.
FPP_KERNEL float or_sign(float r, float s) {
    return std::bit_cast<float>(std::bit_cast<std::uint32_t>(r) |
                                (std::bit_cast<std::uint32_t>(s) & 0x80000000u));
}

// floor() for |x| < 2^31 through an int conversion (vectorises without SSE4.1).
FPP_KERNEL float floor_fast(float x) {
    const std::int32_t i = static_cast<std::int32_t>(x);
    return static_cast<float>(i - static_cast<std::int32_t>(static_cast<float>(i) > x));
}
FPP_KERNEL float ceil_fast(float x) {
    return -floor_fast(-x);
}
// Nearest integer, halves rounded up.
FPP_KERNEL float round_fast(float x) {
    return floor_fast(x + 0.5f);
}
// Nearest integer, halves to even, for |x| < 2^22: adding 1.5 * 2^23 leaves
// no fraction bits, so the addition itself rounds (IEEE round to nearest, the
// default mode; valid without -ffast-math, which could fold the two
// operations). Two operations instead of round_fast's six.
FPP_KERNEL float round_nearest(float x) {
    constexpr float kShift = 12582912.0f; // 1.5 * 2^23
    return (x + kShift) - kShift;
}
FPP_KERNEL float abs_fast(float x) {
    return __builtin_fabsf(x);
}

// atan2(y, x) in [-pi, pi], max error about 2e-7 rad (float rounding; the
// polynomial alone is good to 4e-9). Range reduction: a = min/max of |x|, |y|
// in [0, 1]; a > tan(pi/8) maps to (a - 1)/(a + 1) with pi/4 added, leaving
// |t| <= tan(pi/8) for an odd degree-9 least-squares fit of atan(t) (our own
// fit on Chebyshev nodes). atan2(0, 0) returns 0.
FPP_KERNEL float atan2_fast(float y, float x) {
    const float ax = abs_fast(x);
    const float ay = abs_fast(y);
    const float hi = ax > ay ? ax : ay; // plain operands: maxps / minps
    const float lo = ax > ay ? ay : ax;
    // lo/hi > tan(pi/8): use (lo - hi)/(lo + hi) = (a - 1)/(a + 1). One division.
    const bool reduce = lo > 0.41421356237f * hi;
    const float num = select(reduce, lo - hi, lo);
    float den = select(reduce, lo + hi, hi);
    den = den > 1e-30f ? den : 1e-30f; // lo = hi = 0 gives 0
    const float t = num / den;
    const float u = t * t;
    float r = 7.726177759107e-02f;
    r = r * u - 1.375157727353e-01f;
    r = r * u + 1.996154953981e-01f;
    r = r * u - 3.333218426533e-01f;
    r = r * u + 9.999999030344e-01f;
    r = r * t + (reduce ? kQuarterPi : 0.0f);
    // Octant and quadrant by sign flips plus constants (no select of sums):
    // |y| > |x|: pi/2 - r;  x < 0: pi - r;  y < 0: -r. The first two flips
    // act on r >= +0 (t >= +0, or t >= -tan(pi/8) with pi/4 added; then r or
    // pi/2 - r), where copysign is a plain OR of the sign bit.
    r = or_sign(r, ax - ay) + (ay > ax ? kHalfPi : 0.0f);
    r = or_sign(r, x) + (x < 0.0f ? kPi : 0.0f);
    return __builtin_copysignf(r, y); // r < 0 is possible here (x = -0)
}

// sqrt(v) for v >= 0 by an inverse square root estimate and two Newton
// steps (relative error below 5e-6, plenty for a modulation in DN).
// std::sqrt may set errno, which keeps GCC from vectorising the loop around it.
FPP_KERNEL float sqrt_fast(float v) {
    float y = std::bit_cast<float>(0x5f375a86u - (std::bit_cast<std::uint32_t>(v) >> 1));
    const float half = 0.5f * v;
    y = y * (1.5f - half * y * y);
    y = y * (1.5f - half * y * y);
    return v * y;
}

// Gray code to binary on up to 16 bits (g^-1 of g(n) = n ^ (n >> 1)).
FPP_KERNEL std::uint32_t gray_to_binary(std::uint32_t g) {
    g ^= g >> 1;
    g ^= g >> 2;
    g ^= g >> 4;
    g ^= g >> 8;
    return g;
}

} // namespace fpp::detail
