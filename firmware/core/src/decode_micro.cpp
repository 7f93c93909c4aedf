#include "decode_micro.hpp"

FPP_NO_FP_CONTRACT

namespace fpp::detail {

namespace {

// One other period's prediction c = cos(a + b) = cos a cos b - sin a sin b
// into the sums. Restrict parameters: GCC gives up on that many alias checks.
template <bool First>
FPP_KERNEL void accumulate(int n, const float* __restrict measured, const float* __restrict ca,
                           const float* __restrict sa, float cb, float sb, float* __restrict sum_c,
                           float* __restrict sum_cc, float* __restrict sum_mc) {
    for (int x = 0; x < n; ++x) {
        const float c = ca[x] * cb - sa[x] * sb;
        if constexpr (First) {
            sum_c[x] = c;
            sum_cc[x] = 1.5f + c * c;
            sum_mc[x] = 1.5f + measured[x] * c;
        } else {
            sum_c[x] += c;
            sum_cc[x] += c * c;
            sum_mc[x] += measured[x] * c;
        }
    }
}

// Keeps the best and second-best fit of candidate order k.
FPP_KERNEL void rank(int n, float k, float period, float frames, float lowest, float highest,
                     const float* __restrict frac, const float* __restrict sum_m,
                     const float* __restrict sum_c, const float* __restrict sum_cc,
                     const float* __restrict sum_mc, float* __restrict best,
                     float* __restrict second, float* __restrict best_order) {
    for (int x = 0; x < n; ++x) {
        const float sm = sum_m[x];
        const float sc = sum_c[x];
        const float scc = sum_cc[x];
        const float smc = sum_mc[x];
        // det >= 3/2 n > 0 (Cauchy-Schwarz on the other frames).
        const float fit =
            (scc * sm * sm - 2.0f * sc * sm * smc + frames * smc * smc) / (frames * scc - sc * sc);
        const float p = (frac[x] + k) * period;
        const bool outside = (p < lowest) | (p > highest);
        const float e = select(outside, -3.0e38f, fit);
        const bool better = e > best[x];
        const float runner = e > second[x] ? e : second[x];
        second[x] = select(better, best[x], runner);
        best[x] = select(better, e, best[x]);
        best_order[x] = select(better, k, best_order[x]);
    }
}

} // namespace

// In units of B (m_f = (I_f - A) / B), over all n = F + 2 frames with
// predictions c_j: the fitted sum of squares Q = [S_m, S_mc] M^-1 [S_m, S_mc]^T,
// M = [[n, S_c], [S_c, S_cc]], is what the fit explains; the residual is the
// (candidate-independent) total minus Q, so the best candidate has the largest
// Q. The three shifted frames add 0 to S_m and S_c, 3/2 to S_cc and, at the
// measured phase, 3/2 to S_mc.
FPP_VECTOR_CLONES
void micro_search(int n, const MicroParams& m, float* fraction, const float* modulation,
                  std::uint8_t* ambiguous, float* scratch, int stride) {
    const std::size_t row = static_cast<std::size_t>(stride);
    float* __restrict sum_m = scratch + 3 * static_cast<std::size_t>(m.others) * row;
    float* __restrict sum_c = sum_m + row;
    float* __restrict sum_cc = sum_c + row;
    float* __restrict sum_mc = sum_cc + row;
    float* __restrict best = sum_mc + row;
    float* __restrict second = best + row;
    float* __restrict best_order = second + row;
    const float* frac = fraction; // rewritten in place at the end: no restrict
    for (int x = 0; x < n; ++x) {
        sum_m[x] = 0.0f;
        best[x] = -3.0e38f;
        second[x] = -3.0e38f;
        best_order[x] = 0.0f;
    }
    for (int f = 0; f < m.others; ++f) {
        const float* __restrict measured = scratch + 3 * static_cast<std::size_t>(f) * row;
        for (int x = 0; x < n; ++x)
            sum_m[x] += measured[x];
    }
    const float frames = static_cast<float>(m.others + 3);
    const float period = m.period;
    for (int i = 0; i < m.orders; ++i) {
        const float k = static_cast<float>(m.first_order + i);
        for (int f = 0; f < m.others; ++f) {
            const float* __restrict measured = scratch + 3 * static_cast<std::size_t>(f) * row;
            const float* __restrict ca = measured + row;
            const float* __restrict sa = ca + row;
            const std::size_t at =
                static_cast<std::size_t>(f) * std::size_t(m.orders) + std::size_t(i);
            const float cb = m.order_cos[at];
            const float sb = m.order_sin[at];
            if (f == 0)
                accumulate<true>(n, measured, ca, sa, cb, sb, sum_c, sum_cc, sum_mc);
            else
                accumulate<false>(n, measured, ca, sa, cb, sb, sum_c, sum_cc, sum_mc);
        }
        rank(n, k, period, frames, m.lowest, m.highest, frac, sum_m, sum_c, sum_cc, sum_mc, best,
             second, best_order);
    }
    const float min_gap = m.min_gap;
    for (int x = 0; x < n; ++x) {
        fraction[x] = (frac[x] + best_order[x]) * period;
        const float b = modulation[x];
        // In DN^2: the gap in units of B times B^2.
        const float gap = (best[x] - second[x]) * (b * b);
        ambiguous[x] = gap < min_gap ? std::uint8_t{1} : std::uint8_t{0};
    }
}

} // namespace fpp::detail
