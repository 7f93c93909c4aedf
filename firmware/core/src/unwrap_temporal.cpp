#include "unwrap_temporal.hpp"

#include "fpp/decoder.hpp"
#include "phase_math.hpp"

#include <limits>

FPP_NO_FP_CONTRACT

namespace fpp::detail {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr std::uint32_t kLow = kDecodeLowModulation;
constexpr std::uint32_t kSat = kDecodeSaturated;
constexpr std::uint32_t kBad = kDecodeUnwrapInconsistent;
constexpr std::uint32_t kOutside = kDecodeOutOfRange;

// Flags are built in 32-bit lanes, like the coordinates, and narrowed to the
// mask byte once per pixel: byte-wide flags next to float lanes make GCC pack
// and unpack every intermediate.
FPP_KERNEL std::uint32_t base_flags(float modulation, std::uint8_t sat, const PixelChecks& checks) {
    return (modulation < checks.min_modulation ? kLow : 0u) |
           ((static_cast<std::uint32_t>(sat) & checks.sat_bit) != 0 ? kSat : 0u);
}

// The first axis written assigns the mask; the second ORs into it.
template <bool MaskFirst>
FPP_KERNEL void store(float p, std::uint32_t flags, const PixelChecks& c, float& out,
                      std::uint8_t& mask) {
    const bool outside = (p < c.lowest) | (p > c.highest);
    flags |= outside ? kOutside : 0u;
    out = select(flags != 0, kNaN, p);
    const std::uint32_t bits = flags | (flags == 0 ? std::uint32_t{c.valid_flag} : 0u);
    if constexpr (MaskFirst)
        mask = static_cast<std::uint8_t>(bits);
    else
        mask = static_cast<std::uint8_t>(mask | bits);
}

// Projector window of a block covering the extent: [lo, lo + period).
FPP_KERNEL float window_top(double period, double extent) {
    const double lo = -0.5 - (period - extent) / 2.0;
    return static_cast<float>(lo + period);
}

template <bool MaskFirst>
FPP_KERNEL void direct(int n, const float* __restrict fraction, const float* __restrict modulation,
                       float period, float top, const std::uint8_t* __restrict sat,
                       const PixelChecks& c, float* __restrict out, std::uint8_t* __restrict mask) {
    for (int x = 0; x < n; ++x) {
        float p = fraction[x] * period;
        p -= select(p >= top, period, 0.0f);
        store<MaskFirst>(p, base_flags(modulation[x], sat[x], c), c, out[x], mask[x]);
    }
}

template <bool MaskFirst>
FPP_KERNEL void multi_period(int n, const PhaseRow* blocks, int count, float top,
                             const std::uint8_t* __restrict sat, const PixelChecks& c,
                             float* __restrict out, std::uint8_t* __restrict mask) {
    for (int x = 0; x < n; ++x) {
        std::uint32_t flags = base_flags(blocks[0].modulation[x], sat[x], c);
        float p = blocks[0].fraction[x] * blocks[0].period;
        p -= select(p >= top, blocks[0].period, 0.0f);
        for (int i = 1; i < count; ++i) {
            const PhaseRow& b = blocks[i];
            const float inv = 1.0f / b.period;
            const float pw = b.fraction[x] * b.period;
            const float q = pw + round_nearest((p - pw) * inv) * b.period;
            flags |= abs_fast(q - p) * inv > c.max_disagreement ? kBad : 0u;
            flags |= b.modulation[x] < c.min_modulation ? kLow : 0u;
            p = q;
        }
        store<MaskFirst>(p, flags, c, out[x], mask[x]);
    }
}

template <bool MaskFirst>
FPP_KERNEL void heterodyne(int n, const PhaseRow* blocks, int count,
                           const std::vector<HeterodyneStep>& levels, float top,
                           const std::uint8_t* __restrict sat, const PixelChecks& c,
                           float* __restrict out, std::uint8_t* __restrict mask) {
    const int level_count = static_cast<int>(levels.size());
    for (int x = 0; x < n; ++x) {
        std::uint32_t flags = base_flags(blocks[0].modulation[x], sat[x], c);
        float fraction[3] = {0, 0, 0};
        for (int j = 0; j < count; ++j) {
            fraction[j] = blocks[j].fraction[x];
            flags |= blocks[j].modulation[x] < c.min_modulation ? kLow : 0u;
        }
        float p = 0, weighted = 0, weights = 0;
        for (int l = 0; l < level_count; ++l) {
            const HeterodyneStep& level = levels[static_cast<std::size_t>(l)];
            float f = level.coef[0] * fraction[0] + level.coef[1] * fraction[1] +
                      level.coef[2] * fraction[2];
            f -= floor_fast(f);
            const float pw = f * level.period;
            if (l == 0) {
                p = pw - select(pw >= top, level.period, 0.0f);
            } else {
                const float inv = 1.0f / level.period;
                const float q = pw + round_nearest((p - pw) * inv) * level.period;
                flags |= abs_fast(q - p) * inv > c.max_disagreement ? kBad : 0u;
                p = q;
            }
            if (level.single >= 0) {
                const float w = 1.0f / (level.period * level.period);
                weighted += w * p;
                weights += w;
            }
        }
        const float mean = weighted / select(weights > 0, weights, 1.0f);
        store<MaskFirst>(select(weights > 0, mean, p), flags, c, out[x], mask[x]);
    }
}

// Complementary Gray with the interval centre computed from the code: the
// general form with ceil(), or, when the half period is a whole number of
// pixels, the exact shortcut K unit + unit/2 - 0.5.
// Code step K of a code value: the table of a v2 code, else plain Gray.
template <bool Table> FPP_KERNEL float code_step(std::uint16_t code, const float* table) {
    if constexpr (Table)
        return table[code];
    else
        return static_cast<float>(gray_to_binary(code));
}

template <bool MaskFirst, bool WholeUnit, bool Table = false>
FPP_KERNEL void
complementary_gray(int n, const float* __restrict fraction, const float* __restrict modulation,
                   const std::uint16_t* __restrict code, const GrayRowParams& params,
                   const std::uint8_t* __restrict sat, const PixelChecks& c, float* __restrict out,
                   std::uint8_t* __restrict mask) {
    const float period = params.period;
    const float inv = 1.0f / period;
    const float unit = params.unit;
    const float half_unit = 0.5f * unit - 0.5f;
    const std::uint32_t max_code = params.max_code;
    const float max_dis = c.max_disagreement;
    const float* table = params.step_of_code;
    const float offset = params.offset;
    const float max_step = params.max_step;
    const float wrap_span = params.wrap_span;
    for (int x = 0; x < n; ++x) {
        const float kf = code_step<Table>(code[x], table);
        float centre;
        if constexpr (Table)
            centre =
                0.5f * (ceil_fast(offset + kf * unit) + ceil_fast(offset + (kf + 1.0f) * unit)) -
                0.5f;
        else
            centre = WholeUnit
                         ? kf * unit + half_unit
                         : 0.5f * (ceil_fast(kf * unit) + ceil_fast((kf + 1.0f) * unit)) - 0.5f;
        const float pw = fraction[x] * period;
        float p = pw + round_nearest((centre - pw) * inv) * period;
        if constexpr (Table) {
            const float shift = select(p < -0.5f, wrap_span, 0.0f);
            p += shift;
            centre += shift;
        }
        const bool unused = Table ? kf > max_step : kf > static_cast<float>(max_code);
        const bool inconsistent = unused | (abs_fast(p - centre) * inv > max_dis);
        store<MaskFirst>(p, base_flags(modulation[x], sat[x], c) | (inconsistent ? kBad : 0u), c,
                         out[x], mask[x]);
    }
}

template <bool MaskFirst, bool Table = false>
FPP_KERNEL void plain_gray(int n, const float* __restrict fraction,
                           const float* __restrict modulation, const std::uint16_t* __restrict code,
                           const GrayRowParams& params, const std::uint8_t* __restrict sat,
                           const PixelChecks& c, float* __restrict out,
                           std::uint8_t* __restrict mask, float* __restrict estimate,
                           std::uint8_t* __restrict edge) {
    const float period = params.period;
    const float inv = 1.0f / period;
    const float unit = params.unit;
    const std::uint32_t max_code = params.max_code;
    const float band = params.edge_band;
    const float* table = params.step_of_code;
    const float offset = params.offset;
    const float max_step = params.max_step;
    const float wrap_span = params.wrap_span;
    for (int x = 0; x < n; ++x) {
        const float kf = code_step<Table>(code[x], table);
        float lo, hi;
        if constexpr (Table) {
            lo = ceil_fast(offset + kf * unit) - 0.5f;
            hi = ceil_fast(offset + (kf + 1.0f) * unit) - 0.5f;
        } else {
            lo = ceil_fast(kf * unit) - 0.5f;
            hi = ceil_fast((kf + 1.0f) * unit) - 0.5f;
        }
        const float centre = 0.5f * (lo + hi);
        const float pw = fraction[x] * period;
        float p = pw + round_nearest((centre - pw) * inv) * period;
        if constexpr (Table) {
            const float shift = select(p < -0.5f, wrap_span, 0.0f);
            p += shift;
            lo += shift;
            hi += shift;
        }
        const bool unused = Table ? kf > max_step : kf > static_cast<float>(max_code);
        store<MaskFirst>(p, base_flags(modulation[x], sat[x], c) | (unused ? kBad : 0u), c, out[x],
                         mask[x]);
        estimate[x] = out[x];
        edge[x] = ((p - lo < band) | (hi - p < band)) ? std::uint8_t{1} : std::uint8_t{0};
    }
}

} // namespace

// Each public function picks the loop compiled for its mask_first, so no loop
// tests it per pixel.

FPP_VECTOR_CLONES
void unwrap_direct_row(int n, const PhaseRow& phase, double extent, const std::uint8_t* sat,
                       const PixelChecks& checks, bool mask_first, float* out, std::uint8_t* mask) {
    const PixelChecks c = checks;
    const float top = window_top(double(phase.period), extent);
    if (mask_first)
        direct<true>(n, phase.fraction, phase.modulation, phase.period, top, sat, c, out, mask);
    else
        direct<false>(n, phase.fraction, phase.modulation, phase.period, top, sat, c, out, mask);
}

FPP_VECTOR_CLONES
void unwrap_multi_period_row(int n, const PhaseRow* blocks, int count, double extent,
                             const std::uint8_t* sat, const PixelChecks& checks, bool mask_first,
                             float* out, std::uint8_t* mask) {
    const PixelChecks c = checks;
    const float top = window_top(double(blocks[0].period), extent);
    if (mask_first)
        multi_period<true>(n, blocks, count, top, sat, c, out, mask);
    else
        multi_period<false>(n, blocks, count, top, sat, c, out, mask);
}

FPP_VECTOR_CLONES
void unwrap_heterodyne_row(int n, const PhaseRow* blocks, int count,
                           const std::vector<HeterodyneStep>& levels, double extent,
                           const std::uint8_t* sat, const PixelChecks& checks, bool mask_first,
                           float* out, std::uint8_t* mask) {
    const PixelChecks c = checks;
    const float top = window_top(double(levels[0].period), extent);
    if (mask_first)
        heterodyne<true>(n, blocks, count, levels, top, sat, c, out, mask);
    else
        heterodyne<false>(n, blocks, count, levels, top, sat, c, out, mask);
}

FPP_VECTOR_CLONES
void unwrap_gray_row(int n, const PhaseRow& phase, const std::uint16_t* code,
                     const GrayRowParams& params, const std::uint8_t* sat,
                     const PixelChecks& checks, bool mask_first, float* out, std::uint8_t* mask,
                     float* estimate, std::uint8_t* edge) {
    const PixelChecks c = checks;
    const GrayRowParams g = params;
    const float* f = phase.fraction;
    const float* m = phase.modulation;
    if (g.step_of_code != nullptr) {
        if (!g.complementary) {
            if (mask_first)
                plain_gray<true, true>(n, f, m, code, g, sat, c, out, mask, estimate, edge);
            else
                plain_gray<false, true>(n, f, m, code, g, sat, c, out, mask, estimate, edge);
        } else if (mask_first) {
            complementary_gray<true, false, true>(n, f, m, code, g, sat, c, out, mask);
        } else {
            complementary_gray<false, false, true>(n, f, m, code, g, sat, c, out, mask);
        }
    } else if (!g.complementary) {
        if (mask_first)
            plain_gray<true>(n, f, m, code, g, sat, c, out, mask, estimate, edge);
        else
            plain_gray<false>(n, f, m, code, g, sat, c, out, mask, estimate, edge);
    } else if (g.unit == static_cast<float>(static_cast<std::int32_t>(g.unit))) {
        if (mask_first)
            complementary_gray<true, true>(n, f, m, code, g, sat, c, out, mask);
        else
            complementary_gray<false, true>(n, f, m, code, g, sat, c, out, mask);
    } else {
        if (mask_first)
            complementary_gray<true, false>(n, f, m, code, g, sat, c, out, mask);
        else
            complementary_gray<false, false>(n, f, m, code, g, sat, c, out, mask);
    }
}

namespace {

template <bool MaskFirst, bool Carries>
FPP_KERNEL void code_only(int n, const std::uint16_t* __restrict code, const GrayRowParams& g,
                          const float* __restrict modulation, const std::uint16_t* __restrict doubt,
                          const std::uint8_t* __restrict sat, const PixelChecks& c,
                          float* __restrict out, std::uint8_t* __restrict mask) {
    const float* __restrict table = g.code_coordinate;
    const std::uint32_t count = g.code_count;
    for (int x = 0; x < n; ++x) {
        const std::uint32_t d = doubt[x];
        const std::uint32_t read = code[x];
        std::uint32_t index = read;
        std::uint32_t flags = base_flags(modulation[x], sat[x], c);
        if constexpr (Carries) {
            // run: digits 0..j, j the most significant doubtful one.
            std::uint32_t run = d | (d >> 1u);
            run |= run >> 2u;
            run |= run >> 4u;
            run |= run >> 8u;
            const std::uint32_t top = (run + 1u) >> 1;
            index = run == 0u ? read : count + ((read & ~run) | top);
            flags |= run > g.max_carry_run ? kLow : 0u;
        } else {
            flags |= (d & (d - 1u)) != 0u ? kLow : 0u;
        }
        const float p = table[index];
        flags |= p != p ? kBad : 0u;
        store<MaskFirst>(p, flags, c, out[x], mask[x]);
    }
}

template <bool MaskFirst>
FPP_KERNEL void micro(int n, const float* __restrict coordinate, const float* __restrict modulation,
                      const std::uint8_t* __restrict ambiguous, const std::uint8_t* __restrict sat,
                      const PixelChecks& c, float* __restrict out, std::uint8_t* __restrict mask) {
    for (int x = 0; x < n; ++x)
        store<MaskFirst>(coordinate[x],
                         base_flags(modulation[x], sat[x], c) | (ambiguous[x] != 0 ? kBad : 0u), c,
                         out[x], mask[x]);
}

} // namespace

FPP_VECTOR_CLONES
void unwrap_code_row(int n, const std::uint16_t* code, const GrayRowParams& params,
                     const float* modulation, const std::uint16_t* doubt, const std::uint8_t* sat,
                     const PixelChecks& checks, bool mask_first, float* out, std::uint8_t* mask) {
    const PixelChecks c = checks;
    const GrayRowParams g = params;
    if (g.resolve_carries) {
        if (mask_first)
            code_only<true, true>(n, code, g, modulation, doubt, sat, c, out, mask);
        else
            code_only<false, true>(n, code, g, modulation, doubt, sat, c, out, mask);
    } else {
        if (mask_first)
            code_only<true, false>(n, code, g, modulation, doubt, sat, c, out, mask);
        else
            code_only<false, false>(n, code, g, modulation, doubt, sat, c, out, mask);
    }
}

FPP_VECTOR_CLONES
void unwrap_micro_row(int n, const float* coordinate, const float* modulation,
                      const std::uint8_t* ambiguous, const std::uint8_t* sat,
                      const PixelChecks& checks, bool mask_first, float* out, std::uint8_t* mask) {
    const PixelChecks c = checks;
    if (mask_first)
        micro<true>(n, coordinate, modulation, ambiguous, sat, c, out, mask);
    else
        micro<false>(n, coordinate, modulation, ambiguous, sat, c, out, mask);
}

FPP_VECTOR_CLONES
void flag_row(int n, const PhaseRow& phase, const std::uint8_t* sat, const PixelChecks& checks,
              bool mask_first, std::uint8_t* mask) {
    const std::uint8_t keep = mask_first ? std::uint8_t{0} : std::uint8_t{0xff};
    const float* modulation = phase.modulation;
    const PixelChecks c = checks;
    for (int x = 0; x < n; ++x)
        mask[x] =
            static_cast<std::uint8_t>((mask[x] & keep) | base_flags(modulation[x], sat[x], c));
}

FPP_VECTOR_CLONES
void valid_row(int n, const float* const* coords, int count, std::uint8_t* mask) {
    if (count == 1) {
        const float* a = coords[0];
        for (int x = 0; x < n; ++x)
            mask[x] = static_cast<std::uint8_t>(mask[x] | (a[x] == a[x] ? kDecodeValid : 0));
    } else {
        const float* a = coords[0];
        const float* b = coords[1];
        for (int x = 0; x < n; ++x)
            mask[x] = static_cast<std::uint8_t>(
                mask[x] | (((a[x] == a[x]) & (b[x] == b[x])) ? kDecodeValid : 0));
    }
}

} // namespace fpp::detail
