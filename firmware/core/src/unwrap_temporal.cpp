#include "unwrap_temporal.hpp"

#include "fpp/decoder.hpp"
#include "phase_math.hpp"

#include <limits>

FPP_NO_FP_CONTRACT

namespace fpp::detail {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

FPP_KERNEL std::uint8_t base_flags(float modulation, std::uint8_t sat, const PixelChecks& checks) {
    return static_cast<std::uint8_t>((modulation < checks.min_modulation ? kDecodeLowModulation : 0) |
                                     ((sat & checks.sat_bit) != 0 ? kDecodeSaturated : 0));
}

// `keep` is 0 for the first axis written (assign) and 0xff after (OR); an
// unconditional read keeps the loops free of branches.
FPP_KERNEL void store(float p, std::uint8_t flags, std::uint8_t keep, const PixelChecks& c,
                  float& out, std::uint8_t& mask) {
    const bool outside = (p < c.lowest) | (p > c.highest);
    flags = static_cast<std::uint8_t>(flags | (outside ? kDecodeUnwrapInconsistent : 0));
    out = select(flags != 0, kNaN, p);
    mask = static_cast<std::uint8_t>((mask & keep) | flags | (flags == 0 ? c.valid_flag : 0));
}

// Complementary Gray with the interval centre computed from the code: the
// general form with ceil(), or, when the half period is a whole number of
// pixels, the exact shortcut K unit + unit/2 - 0.5.
template <bool WholeUnit>
FPP_KERNEL void unwrap_complementary_gray(int n, const float* fraction, const float* modulation,
                               const std::uint16_t* code, const GrayRowParams& params,
                               const std::uint8_t* sat, const PixelChecks& c, std::uint8_t keep,
                               float* out, std::uint8_t* mask) {
    const float period = params.period;
    const float inv = 1.0f / period;
    const float unit = params.unit;
    const float half_unit = 0.5f * unit - 0.5f;
    const std::uint32_t max_code = params.max_code;
    const float max_dis = c.max_disagreement;
    for (int x = 0; x < n; ++x) {
        const std::uint32_t k = gray_to_binary(code[x]);
        const float kf = static_cast<float>(k);
        const float centre =
            WholeUnit ? kf * unit + half_unit
                      : 0.5f * (ceil_fast(kf * unit) + ceil_fast((kf + 1.0f) * unit)) - 0.5f;
        const float pw = fraction[x] * period;
        const float p = pw + round_fast((centre - pw) * inv) * period;
        const bool inconsistent = (k > max_code) | (abs_fast(p - centre) * inv > max_dis);
        const std::uint8_t flags = static_cast<std::uint8_t>(
            base_flags(modulation[x], sat[x], c) | (inconsistent ? kDecodeUnwrapInconsistent : 0));
        store(p, flags, keep, c, out[x], mask[x]);
    }
}

FPP_KERNEL std::uint8_t keep_mask(bool mask_first) { return mask_first ? std::uint8_t{0} : std::uint8_t{0xff}; }

// Projector window of a block covering the extent: [lo, lo + period).
FPP_KERNEL float window_top(double period, double extent) {
    const double lo = -0.5 - (period - extent) / 2.0;
    return static_cast<float>(lo + period);
}

} // namespace

FPP_VECTOR_CLONES
void unwrap_direct_row(int n, const PhaseRow& phase, double extent, const std::uint8_t* sat,
                       const PixelChecks& checks, bool mask_first, float* out,
                       std::uint8_t* mask) {
    const std::uint8_t keep = keep_mask(mask_first);
    const float period = phase.period;
    const float top = window_top(period, extent);
    const float* fraction = phase.fraction;
    const float* modulation = phase.modulation;
    const PixelChecks c = checks;
    for (int x = 0; x < n; ++x) {
        float p = fraction[x] * period;
        p -= select(p >= top, period, 0.0f);
        const std::uint8_t flags = base_flags(modulation[x], sat[x], c);
        store(p, flags, keep, c, out[x], mask[x]);
    }
}

FPP_VECTOR_CLONES
void unwrap_multi_period_row(int n, const PhaseRow* blocks, int count, double extent,
                             const std::uint8_t* sat, const PixelChecks& checks, bool mask_first,
                             float* out, std::uint8_t* mask) {
    const std::uint8_t keep = keep_mask(mask_first);
    const float top = window_top(blocks[0].period, extent);
    for (int x = 0; x < n; ++x) {
        std::uint8_t flags = base_flags(blocks[0].modulation[x], sat[x], checks);
        float p = blocks[0].fraction[x] * blocks[0].period;
        p -= select(p >= top, blocks[0].period, 0.0f);
        for (int i = 1; i < count; ++i) {
            const PhaseRow& b = blocks[i];
            const float inv = 1.0f / b.period;
            const float pw = b.fraction[x] * b.period;
            const float q = pw + round_fast((p - pw) * inv) * b.period;
            if (abs_fast(q - p) * inv > checks.max_disagreement) flags |= kDecodeUnwrapInconsistent;
            if (b.modulation[x] < checks.min_modulation) flags |= kDecodeLowModulation;
            p = q;
        }
        store(p, flags, keep, checks, out[x], mask[x]);
    }
}

FPP_VECTOR_CLONES
void unwrap_heterodyne_row(int n, const PhaseRow* blocks, int count,
                           const std::vector<HeterodyneStep>& levels, double extent,
                           const std::uint8_t* sat, const PixelChecks& checks, bool mask_first,
                           float* out, std::uint8_t* mask) {
    const std::uint8_t keep = keep_mask(mask_first);
    const float top = window_top(levels[0].period, extent);
    const int level_count = static_cast<int>(levels.size());
    for (int x = 0; x < n; ++x) {
        std::uint8_t flags = base_flags(blocks[0].modulation[x], sat[x], checks);
        float fraction[3] = {0, 0, 0};
        for (int j = 0; j < count; ++j) {
            fraction[j] = blocks[j].fraction[x];
            if (blocks[j].modulation[x] < checks.min_modulation) flags |= kDecodeLowModulation;
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
                const float q = pw + round_fast((p - pw) * inv) * level.period;
                if (abs_fast(q - p) * inv > checks.max_disagreement)
                    flags |= kDecodeUnwrapInconsistent;
                p = q;
            }
            if (level.single >= 0) {
                const float w = 1.0f / (level.period * level.period);
                weighted += w * p;
                weights += w;
            }
        }
        const float mean = weighted / select(weights > 0, weights, 1.0f);
        store(select(weights > 0, mean, p), flags, keep, checks, out[x], mask[x]);
    }
}

FPP_VECTOR_CLONES
void unwrap_gray_row(int n, const PhaseRow& phase, const std::uint16_t* code,
                     const GrayRowParams& params, const std::uint8_t* sat,
                     const PixelChecks& checks, bool mask_first, float* out, std::uint8_t* mask,
                     float* estimate, std::uint8_t* edge) {
    const std::uint8_t keep = keep_mask(mask_first);
    const float period = params.period;
    const float inv = 1.0f / period;
    const float unit = params.unit;
    const std::uint32_t max_code = params.max_code;
    const float* fraction = phase.fraction;
    const float* modulation = phase.modulation;
    const PixelChecks c = checks;
    if (params.complementary) {
        if (unit == static_cast<float>(static_cast<std::int32_t>(unit)))
            unwrap_complementary_gray<true>(n, fraction, modulation, code, params, sat, c, keep,
                                            out, mask);
        else
            unwrap_complementary_gray<false>(n, fraction, modulation, code, params, sat, c, keep,
                                             out, mask);
    } else {
        const float band = params.edge_band;
        for (int x = 0; x < n; ++x) {
            const std::uint32_t k = gray_to_binary(code[x]);
            const float kf = static_cast<float>(k);
            const float lo = ceil_fast(kf * unit) - 0.5f;
            const float hi = ceil_fast((kf + 1.0f) * unit) - 0.5f;
            const float centre = 0.5f * (lo + hi);
            const float pw = fraction[x] * period;
            const float p = pw + round_fast((centre - pw) * inv) * period;
            const std::uint8_t flags = static_cast<std::uint8_t>(
                base_flags(modulation[x], sat[x], c) |
                (k > max_code ? kDecodeUnwrapInconsistent : 0));
            store(p, flags, keep, c, out[x], mask[x]);
            estimate[x] = out[x];
            edge[x] = ((p - lo < band) | (hi - p < band)) ? std::uint8_t{1} : std::uint8_t{0};
        }
    }
}

FPP_VECTOR_CLONES
void flag_row(int n, const PhaseRow& phase, const std::uint8_t* sat, const PixelChecks& checks,
              bool mask_first, std::uint8_t* mask) {
    const std::uint8_t keep = keep_mask(mask_first);
    const float* modulation = phase.modulation;
    const PixelChecks c = checks;
    for (int x = 0; x < n; ++x) {
        const std::uint8_t flags = base_flags(modulation[x], sat[x], c);
        mask[x] = static_cast<std::uint8_t>((mask[x] & keep) | flags);
    }
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
                mask[x] | ((a[x] == a[x]) & (b[x] == b[x]) ? kDecodeValid : 0));
    }
}

} // namespace fpp::detail
