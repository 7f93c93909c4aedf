#include "decode_micro.hpp"

#include <algorithm>

FPP_NO_FP_CONTRACT

namespace fpp::detail {

namespace {

// Pixels searched together: every candidate order runs over a chunk of this
// many pixels, whose samples and sums stay in L1. A loop over every order for
// a whole row instead streams 3 (F - 1) + 7 rows of scratch through L2 once
// per order (1.45x slower). GCC vectorises the lane loops at this count; at
// 16 it unrolls them instead (8x slower).
constexpr int kLanes = 64;
constexpr int kMaxOthers = 15; // check_micro: at most 16 periods

// Every kSampleStep-th pixel of a row is searched over every order; the
// pixels around it then over its order +- kMargin (see micro_search).
constexpr int kSampleStep = 16;
constexpr int kMargin = 2;
constexpr float kNoOrder = -1.0f; // a sample without a clear order
// A windowed pixel needs B^2 >= kStrong^2 min_gap (B >= 28 DN at 8 bits) and
// a residual of at most kFitShare min_gap. Measured on five scenes of the
// effects rig (composite, ball-bar, relief, sphere, hdr-parts): kStrong 3
// keeps every scene's gross errors at the full search's count; 2 adds one on
// the sphere and one on hdr-parts; without it hdr-parts gets 426 more, on
// pixels of B 10 to 15 DN. Samples every 32 px add 1 on the sphere.
constexpr float kStrong = 3.0f;
constexpr float kFitShare = 0.25f;

// The best and second-best fit Q, the best order's index and the candidate-
// independent total sum of squares T (units of B^2) of one chunk's pixels.
struct ChunkFit {
    float best[kLanes];
    float second[kLanes];
    float order[kLanes];
    float total[kLanes];
};

// Order indices [first, last) into the plan's candidate orders.
struct Window {
    int first = 0, last = 0;
};

// At most one window per sample a chunk sees (windows_of).
constexpr int kMaxWindows = kLanes / kSampleStep + 3;

// One chunk's samples: per other period the measured cosine and the cos / sin
// of its phase at order 0 (micro_base_row's rows), and the first period's
// wrapped fraction.
struct ChunkSamples {
    float measured[kMaxOthers][kLanes];
    float ca[kMaxOthers][kLanes];
    float sa[kMaxOthers][kLanes];
    float frac[kLanes];
    float modulation[kLanes]; // B, DN
};

// Pixels x0 .. x0 + kLanes - 1, those at or past x1 repeating x1 - 1.
FPP_KERNEL void load_run(const MicroParams& m, int x0, int x1, const float* frac,
                         const float* modulation, const float* scratch, std::size_t row,
                         ChunkSamples& in) {
    const bool full = x1 - x0 == kLanes;
    const auto copy = [&](const float* from, float* to) {
        if (full) { // contiguous: vector loads
            for (int l = 0; l < kLanes; ++l)
                to[l] = from[x0 + l];
        } else {
            for (int l = 0; l < kLanes; ++l)
                to[l] = from[std::min(x0 + l, x1 - 1)];
        }
    };
    copy(frac, in.frac);
    copy(modulation, in.modulation);
    for (int f = 0; f < m.others; ++f) {
        const float* base = scratch + 3 * static_cast<std::size_t>(f) * row;
        copy(base, in.measured[f]);
        copy(base + row, in.ca[f]);
        copy(base + 2 * row, in.sa[f]);
    }
}

// The pixels `pixels` (kLanes of them, repeats allowed).
FPP_KERNEL void load_pixels(const MicroParams& m, const int* pixels, const float* frac,
                            const float* modulation, const float* scratch, std::size_t row,
                            ChunkSamples& in) {
    for (int l = 0; l < kLanes; ++l) {
        const auto x = static_cast<std::size_t>(pixels[l]);
        in.frac[l] = frac[x];
        in.modulation[l] = modulation[x];
        for (int f = 0; f < m.others; ++f) {
            const float* base = scratch + 3 * static_cast<std::size_t>(f) * row;
            in.measured[f][l] = base[x];
            in.ca[f][l] = base[row + x];
            in.sa[f][l] = base[2 * row + x];
        }
    }
}

// The orders of `windows` for the chunk's samples.
FPP_KERNEL void fit_orders(const MicroParams& m, const ChunkSamples& in, const Window* windows,
                           int window_count, ChunkFit& out) {
    const auto& measured = in.measured;
    const auto& ca = in.ca;
    const auto& sa = in.sa;
    const float* fr = in.frac;
    float sum_m[kLanes];
    for (int l = 0; l < kLanes; ++l) {
        sum_m[l] = 0.0f;
        out.total[l] = 1.5f; // the three shifted frames' cos^2
        out.best[l] = -3.0e38f;
        out.second[l] = -3.0e38f;
        out.order[l] = 0.0f;
    }
    for (int f = 0; f < m.others; ++f)
        for (int l = 0; l < kLanes; ++l) {
            sum_m[l] += measured[f][l];
            out.total[l] += measured[f][l] * measured[f][l];
        }
    const float frames = static_cast<float>(m.others + 3);
    for (int w = 0; w < window_count; ++w) {
        for (int i = windows[w].first; i < windows[w].last; ++i) {
            const float k = static_cast<float>(m.first_order + i);
            // The three shifted frames add 0 to S_c, 3/2 to S_cc and S_mc.
            float sum_c[kLanes], sum_cc[kLanes], sum_mc[kLanes];
            for (int l = 0; l < kLanes; ++l) {
                sum_c[l] = 0.0f;
                sum_cc[l] = 1.5f;
                sum_mc[l] = 1.5f;
            }
            for (int f = 0; f < m.others; ++f) {
                const std::size_t at =
                    static_cast<std::size_t>(f) * std::size_t(m.orders) + std::size_t(i);
                const float cb = m.order_cos[at];
                const float sb = m.order_sin[at];
                // cos(a + b) = cos a cos b - sin a sin b: this period's prediction.
                for (int l = 0; l < kLanes; ++l) {
                    const float c = ca[f][l] * cb - sa[f][l] * sb;
                    sum_c[l] += c;
                    sum_cc[l] += c * c;
                    sum_mc[l] += measured[f][l] * c;
                }
            }
            for (int l = 0; l < kLanes; ++l) {
                const float sm = sum_m[l];
                const float sc = sum_c[l];
                const float scc = sum_cc[l];
                const float smc = sum_mc[l];
                // det >= 3/2 n > 0 (Cauchy-Schwarz on the other frames).
                const float fit = (scc * sm * sm - 2.0f * sc * sm * smc + frames * smc * smc) /
                                  (frames * scc - sc * sc);
                const float p = (fr[l] + k) * m.period;
                const bool outside = (p < m.lowest) | (p > m.highest);
                const float e = select(outside, -3.0e38f, fit);
                const bool better = e > out.best[l];
                const float runner = e > out.second[l] ? e : out.second[l];
                out.second[l] = select(better, out.best[l], runner);
                out.best[l] = select(better, e, out.best[l]);
                out.order[l] = select(better, static_cast<float>(i), out.order[l]);
            }
        }
    }
}

// The gap between the two best fits in DN^2 (units of B^2 times B^2).
inline float gap_dn2(const ChunkFit& fit, int lane, float modulation) {
    return (fit.best[lane] - fit.second[lane]) * (modulation * modulation);
}

// Adds [w.first, w.last) to the `count` sorted, disjoint windows, merging
// those it meets. Returns the new count.
inline int add_window(Window w, Window* windows, int count) {
    int at = 0;
    while (at < count && windows[at].last < w.first)
        ++at;
    int end = at;
    while (end < count && windows[end].first <= w.last) {
        w.first = std::min(w.first, windows[end].first);
        w.last = std::max(w.last, windows[end].last);
        ++end;
    }
    if (end == at) {
        for (int k = count; k > at; --k)
            windows[k] = windows[k - 1];
        ++count;
    } else {
        for (int k = end; k < count; ++k)
            windows[k - (end - at) + 1] = windows[k];
        count -= end - at - 1;
    }
    windows[at] = w;
    return count;
}

// The windows of orders for the pixels [x0, x1): each sample among them and
// the one either side with a clear order gives that order +- kMargin. None
// when no sample has one.
inline int windows_of(const float* sample_order, int samples, int x0, int x1, int orders,
                      Window* windows) {
    const int s0 = std::max(x0 / kSampleStep - 1, 0);
    const int s1 = std::min((x1 - 1) / kSampleStep + 1, samples - 1);
    int count = 0;
    for (int s = s0; s <= s1; ++s) {
        if (sample_order[s] == kNoOrder)
            continue;
        const int order = static_cast<int>(sample_order[s]);
        count = add_window({std::max(order - kMargin, 0), std::min(order + kMargin + 1, orders)},
                           windows, count);
    }
    return count;
}

// What resolve_chunk makes of one chunk: each lane's column (its wrapped
// fraction, unchanged, when it must be searched again) and flags.
struct ChunkVerdict {
    static constexpr std::uint8_t kAmbiguous = 1, kAgain = 2;
    float column[kLanes];
    std::uint8_t flags[kLanes];
};

// Resolves a chunk from `fit`: with `every` (every order searched) by the
// gap alone. Otherwise a pixel keeps its window's best order when that order
// is not on a window edge that is not also an end of the order range, its
// window gap is clear, its modulation strong and its fit within the noise;
// else it is dropped (ambiguous) when its modulation is below the validity
// floor, as it is masked anyway, and marked to be searched over every order.
FPP_KERNEL void resolve_chunk(const MicroParams& m, const ChunkSamples& in, const ChunkFit& fit,
                              const Window* windows, int count, bool every, ChunkVerdict& out) {
    float inside[kLanes]; // 0 or 1
    for (int l = 0; l < kLanes; ++l)
        inside[l] = 0.0f;
    for (int w = 0; w < count; ++w) {
        const auto lo = static_cast<float>(windows[w].first + (windows[w].first > 0 ? 1 : 0));
        const auto hi = static_cast<float>(windows[w].last - (windows[w].last < m.orders ? 1 : 0));
        for (int l = 0; l < kLanes; ++l)
            inside[l] = select((fit.order[l] >= lo) & (fit.order[l] < hi), 1.0f, inside[l]);
    }
    const float strong = kStrong * kStrong * m.min_gap;
    const float noise = kFitShare * m.min_gap;
    const auto first_order = static_cast<float>(m.first_order);
    for (int l = 0; l < kLanes; ++l) {
        const float b = in.modulation[l];
        const float b2 = b * b;
        const bool clear = (fit.best[l] - fit.second[l]) * b2 >= m.min_gap;
        const bool trusted =
            (inside[l] > 0.5f) & (b2 >= strong) & ((fit.total[l] - fit.best[l]) * b2 <= noise);
        const bool keep = clear & (every | trusted);
        const bool again = !every & !keep & (b >= m.min_modulation);
        const float k = first_order + fit.order[l]; // exact: small integers
        out.column[l] = select(again, in.frac[l], (in.frac[l] + k) * m.period);
        out.flags[l] = static_cast<std::uint8_t>((keep ? 0 : ChunkVerdict::kAmbiguous) |
                                                 (again ? ChunkVerdict::kAgain : 0));
    }
}

// Every kSampleStep-th pixel's best order over every order into `order`, or
// kNoOrder where that order is not clear: the full search's decision.
FPP_KERNEL void sample_orders(int n, const MicroParams& m, const float* frac,
                              const float* modulation, const float* scratch, std::size_t row,
                              float* order) {
    const int samples = (n + kSampleStep - 1) / kSampleStep;
    const Window all{0, m.orders};
    int pixels[kLanes];
    ChunkSamples in;
    ChunkFit fit;
    for (int s0 = 0; s0 < samples; s0 += kLanes) {
        const int count = std::min(samples - s0, kLanes);
        for (int l = 0; l < kLanes; ++l)
            pixels[l] = (s0 + std::min(l, count - 1)) * kSampleStep;
        load_pixels(m, pixels, frac, modulation, scratch, row, in);
        fit_orders(m, in, &all, 1, fit);
        for (int l = 0; l < count; ++l)
            order[s0 + l] =
                gap_dn2(fit, l, in.modulation[l]) >= m.min_gap ? fit.order[l] : kNoOrder;
    }
}

} // namespace

// In units of B (m_f = (I_f - A) / B), over all n = F + 2 frames with
// predictions c_j: the fitted sum of squares Q = [S_m, S_mc] M^-1 [S_m, S_mc]^T,
// M = [[n, S_c], [S_c, S_cc]], is what the fit explains; the residual is the
// (candidate-independent) total T minus Q, so the best candidate has the
// largest Q. The three shifted frames add 0 to S_m and S_c, 3/2 to S_cc and,
// at the measured phase, 3/2 to S_mc.
//
// A column moves by a few fringe orders over a few dozen pixels of a row, so
// most pixels need not try every order. Every kSampleStep-th pixel is
// searched over every order (the full search); each chunk of kLanes pixels
// then over the orders its samples found, +- kMargin. A pixel keeps its
// window's best order when resolve_chunk says so, is dropped when its
// modulation is below the validity floor (it is masked anyway), and is
// searched over every order otherwise. A kept order can differ from the full
// search's only where an order outside the window fits better by less than
// min_gap: a pixel the full search would flag ambiguous, which the row's
// samples resolve instead. A chunk whose windows cover more than half the
// orders is searched in full.
FPP_VECTOR_CLONES
void micro_search(int n, const MicroParams& m, float* fraction, const float* modulation,
                  std::uint8_t* ambiguous, float* scratch, int stride) {
    const std::size_t row = static_cast<std::size_t>(stride);
    const Window all{0, m.orders};
    ChunkSamples in;
    ChunkFit fit;
    ChunkVerdict verdict;
    float* sample_order = scratch + 3 * static_cast<std::size_t>(m.others) * row;
    float* retry = sample_order + row; // pixel indices, exact as floats below 2^24
    const int samples = (n + kSampleStep - 1) / kSampleStep;
    if (!m.every_order)
        sample_orders(n, m, fraction, modulation, scratch, row, sample_order);
    Window windows[kMaxWindows];
    int retries = 0;
    for (int x0 = 0; x0 < n; x0 += kLanes) {
        const int x1 = std::min(n, x0 + kLanes);
        int count = 0;
        bool every = m.every_order;
        if (!every) {
            count = windows_of(sample_order, samples, x0, x1, m.orders, windows);
            int searched = 0;
            for (int w = 0; w < count; ++w)
                searched += windows[w].last - windows[w].first;
            every = 2 * searched > m.orders;
        }
        if (every) {
            windows[0] = all;
            count = 1;
        }
        load_run(m, x0, x1, fraction, modulation, scratch, row, in);
        fit_orders(m, in, windows, count, fit);
        resolve_chunk(m, in, fit, windows, count, every, verdict);
        std::uint8_t any_again = 0;
        for (int l = 0; l < x1 - x0; ++l) {
            fraction[x0 + l] = verdict.column[l];
            ambiguous[x0 + l] = verdict.flags[l] & ChunkVerdict::kAmbiguous;
            any_again |= verdict.flags[l];
        }
        if ((any_again & ChunkVerdict::kAgain) != 0)
            for (int l = 0; l < x1 - x0; ++l) {
                retry[retries] = static_cast<float>(x0 + l); // branch-free append
                retries += verdict.flags[l] >> 1;
            }
    }
    int pixels[kLanes];
    for (int r0 = 0; r0 < retries; r0 += kLanes) {
        const int r1 = std::min(retries, r0 + kLanes);
        for (int l = 0; l < kLanes; ++l)
            pixels[l] = static_cast<int>(retry[std::min(r0 + l, r1 - 1)]);
        load_pixels(m, pixels, fraction, modulation, scratch, row, in);
        fit_orders(m, in, &all, 1, fit);
        resolve_chunk(m, in, fit, &all, 1, true, verdict);
        for (int l = 0; l < r1 - r0; ++l) {
            fraction[pixels[l]] = verdict.column[l];
            ambiguous[pixels[l]] = verdict.flags[l] & ChunkVerdict::kAmbiguous;
        }
    }
}

} // namespace fpp::detail
