#pragma once
// Phase-shift weights grouped by value. For an N-step block (delta_k =
// 2 pi k / N) the weights cos(delta_k) take about N/4 + 1 distinct magnitudes
// and sin(delta_k) about N/4, each shared by several frames with a sign. The
// sums are formed class by class:
//   C = sum_j Wc[j] Sc[j],  Sc[j] = sum of sign_k I_k over the frames k of class j
// (S likewise). The class sums are integer sums of the samples, exact in any
// order, and each is multiplied by its weight once: a fraction of the float
// operations of a frame-by-frame weighted sum, and more accurate. Frames whose
// weight is zero (cos(pi/2), sin(0), sin(pi)) drop out.
//
// cos class j has weight cos(2 pi j / N); sin class j has weight
// sin(2 pi (j + 1) / N) (times -shift_sign, see decode_plan.hpp).

namespace fpp::detail {

// Blocks of up to this many steps use classes: their decoding kernels are
// compiled for each N, and class sums fit 16 bits for 8-bit samples.
inline constexpr int kMaxClassSteps = 16;

struct WeightClass {
    int index = 0;
    int sign = 0; // +1, -1, or 0 for a zero weight
};

// m in [0, N/2] with cos(2 pi k / N) = cos(2 pi m / N).
constexpr int class_angle(int n, int k) {
    return k <= n - k ? k : n - k;
}

// cos(2 pi k / N) = sign * cos(2 pi index / N).
constexpr WeightClass cos_class(int n, int k) {
    const int m = class_angle(n, k);
    if (n % 2 == 0) {
        if (4 * m == n)
            return {0, 0};
        if (4 * m > n)
            return {n / 2 - m, -1}; // cos(pi - x) = -cos(x)
    }
    return {m, 1};
}

// sin(2 pi k / N) = sign * sin(2 pi (index + 1) / N).
constexpr WeightClass sin_class(int n, int k) {
    int m = class_angle(n, k);
    const int sign = k <= n - k ? 1 : -1; // sin(2 pi - x) = -sin(x)
    if (m == 0 || 2 * m == n)
        return {0, 0};
    if (n % 2 == 0 && 4 * m > n)
        m = n / 2 - m; // sin(pi - x) = sin(x)
    return {m - 1, sign};
}

constexpr int cos_class_count(int n) {
    int count = 0;
    for (int k = 0; k < n; ++k)
        if (cos_class(n, k).sign != 0 && cos_class(n, k).index + 1 > count)
            count = cos_class(n, k).index + 1;
    return count;
}

constexpr int sin_class_count(int n) {
    int count = 0;
    for (int k = 0; k < n; ++k)
        if (sin_class(n, k).sign != 0 && sin_class(n, k).index + 1 > count)
            count = sin_class(n, k).index + 1;
    return count;
}

} // namespace fpp::detail
