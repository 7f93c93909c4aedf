#pragma once
// Counter-based random numbers for sensor noise (internal): the value for
// pixel i of a frame depends only on (seed, i), so renders are reproducible
// and independent of how rows are split among threads.

#include <cmath>
#include <cstdint>

namespace fpp::sim::detail {

// SplitMix64 finaliser: a bijective 64-bit mix with good avalanche.
inline std::uint64_t mix64(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

// Standard normal quantile (inverse CDF), P. J. Acklam's rational
// approximation (relative error < 1.2e-9): a rational function in the
// centre, which needs no transcendental call for 95 % of samples.
inline double normal_quantile(double p) {
    constexpr double a1 = -3.969683028665376e+01, a2 = 2.209460984245205e+02,
                     a3 = -2.759285104469687e+02, a4 = 1.383577518672690e+02,
                     a5 = -3.066479806614716e+01, a6 = 2.506628277459239e+00;
    constexpr double b1 = -5.447609879822406e+01, b2 = 1.615858368580409e+02,
                     b3 = -1.556989798598866e+02, b4 = 6.680131188771972e+01,
                     b5 = -1.328068155288572e+01;
    constexpr double c1 = -7.784894002430293e-03, c2 = -3.223964580411365e-01,
                     c3 = -2.400758277161838e+00, c4 = -2.549671010422325e+00,
                     c5 = 4.374664141464968e+00, c6 = 2.938163982698783e+00;
    constexpr double d1 = 7.784695709041462e-03, d2 = 3.224671290700398e-01,
                     d3 = 2.445134137142996e+00, d4 = 3.754408661907416e+00;
    constexpr double p_low = 0.02425;
    if (p < p_low || p > 1 - p_low) {
        const double tail = p < p_low ? p : 1 - p;
        const double q = std::sqrt(-2 * std::log(tail));
        const double x = (((((c1 * q + c2) * q + c3) * q + c4) * q + c5) * q + c6) /
                         ((((d1 * q + d2) * q + d3) * q + d4) * q + 1);
        return p < p_low ? x : -x;
    }
    const double q = p - 0.5;
    const double r = q * q;
    return (((((a1 * r + a2) * r + a3) * r + a4) * r + a5) * r + a6) * q /
           (((((b1 * r + b2) * r + b3) * r + b4) * r + b5) * r + 1);
}

// Standard normal samples, fast: the quantile function tabulated at 4096
// equal steps of probability and interpolated linearly (error < 0.003 sigma
// in the outermost interpolated bins, far less in the centre); the two
// extreme bins (p < 1/4096 or p > 4095/4096) use the exact formula.
class NormalTable {
public:
    static constexpr int kBits = 12;
    static constexpr int kSize = 1 << kBits;

    NormalTable() {
        for (int i = 1; i < kSize; ++i)
            table_[i] = static_cast<float>(normal_quantile(static_cast<double>(i) / kSize));
        table_[0] = table_[1];             // unused (exact tail)
        table_[kSize] = table_[kSize - 1]; // unused (exact tail)
    }

    // Standard normal for pixel `counter` of the frame keyed by `key`.
    float operator()(std::uint64_t key, std::uint64_t counter) const {
        const std::uint64_t r = mix64(key + counter * 0x9e3779b97f4a7c15ULL);
        const unsigned bin = static_cast<unsigned>(r >> (64 - kBits));
        if (bin == 0 || bin == kSize - 1) [[unlikely]]
            return static_cast<float>(
                normal_quantile((static_cast<double>(r >> 11) + 0.5) * 0x1.0p-53));
        // 24 bits below the bin index give the position inside the bin.
        const float frac = static_cast<float>((r >> (64 - kBits - 24)) & 0xffffff) * 0x1.0p-24f;
        return table_[bin] + frac * (table_[bin + 1] - table_[bin]);
    }

private:
    float table_[kSize + 1]{};
};

} // namespace fpp::sim::detail
