// The decoding steps of the fpp-capture/2 families (decode_engine.hpp):
// 2+1, modulated and micro phase blocks, n-ary code digits, the white and
// black level planes and the modulation of code-only axes.

#include "decode_engine.hpp"
#include "decode_family_kernels.hpp"
#include "decode_micro.hpp"

#include <algorithm>
#include <cstdint>

FPP_NO_FP_CONTRACT

namespace fpp::detail {

template <class T>
FPP_VECTOR_CLONES void DecodeEngine::run_family_block(const Step& step, std::size_t offset, int n,
                                                      std::byte* local, float* scratch) const {
    const PhaseInfo& p = plan_.phases[static_cast<std::size_t>(step.index)];
    const PhaseState& ps = phase_state_[static_cast<std::size_t>(step.index)];
    float* c = at(ps.fraction, offset, local);
    float* sn = at(ps.modulation, offset, local);
    float* a = at(ps.mean, offset, local);
    const T level = static_cast<T>(sat_level_);
    std::uint8_t* sat = at(sat_, offset, local);
    T* threshold = p.thresholds ? threshold_at<T>(ps.threshold, offset, local) : nullptr;
    switch (p.kind) {
    case PhaseKind::two_plus_one: {
        const SatUpdate update{sat, step.sat_bits,
                               step.sat_first ? std::uint8_t{0} : std::uint8_t{0xff}};
        two_plus_one_row<T>(frame_at<T>(step.frame, offset), frame_at<T>(step.frame + 1, offset),
                            frame_at<T>(step.frame + 2, offset), n,
                            static_cast<float>(p.block.shift_sign), level, update, c, sn, a);
        phase_finish_row<T>(n, 1.0f, 1.0f, p.offset_fraction, c, sn, a, threshold);
        return;
    }
    case PhaseKind::modulated: {
        const int steps = p.block.steps;
        const int carriers = p.block.carrier_steps;
        const std::size_t row = static_cast<std::size_t>(span_);
        float* cr = scratch;
        float* sr = scratch + row;
        float* raw = scratch + 2 * row;
        const float two_over_m = 2.0f / static_cast<float>(carriers);
        if (carriers == 3 || carriers == 4) {
            // One pass per shift (the common carriers), same arithmetic.
            for (int i = 0; i < steps; ++i) {
                const T* in[4];
                for (int j = 0; j < carriers; ++j)
                    in[j] = frame_at<T>(step.frame + i * carriers + j, offset);
                const SatUpdate update{sat, step.sat_bits,
                                       i == 0 && step.sat_first ? std::uint8_t{0}
                                                                : std::uint8_t{0xff}};
                const float wc = p.cos_w[static_cast<std::size_t>(i)];
                const float ws = p.sin_w[static_cast<std::size_t>(i)];
                if (carriers == 3)
                    modulated_shift_row<T, 3>(in, n, p.carrier_cos.data(), p.carrier_sin.data(),
                                              two_over_m, wc, ws, i == 0, level, update, c, sn, a,
                                              raw);
                else
                    modulated_shift_row<T, 4>(in, n, p.carrier_cos.data(), p.carrier_sin.data(),
                                              two_over_m, wc, ws, i == 0, level, update, c, sn, a,
                                              raw);
            }
        }
        for (int i = 0; carriers != 3 && carriers != 4 && i < steps; ++i) {
            for (int j = 0; j < carriers; ++j) {
                const int frame = step.frame + i * carriers + j;
                const T* in = frame_at<T>(frame, offset);
                const bool first_frame = i == 0 && j == 0;
                saturation_row(in, n, level, step.sat_bits, first_frame && step.sat_first, sat);
                carrier_frame_row<T>(in, n, p.carrier_cos[static_cast<std::size_t>(j)],
                                     p.carrier_sin[static_cast<std::size_t>(j)], j == 0,
                                     first_frame, cr, sr, raw);
            }
            carrier_amplitude_row(n, two_over_m, p.cos_w[static_cast<std::size_t>(i)],
                                  p.sin_w[static_cast<std::size_t>(i)], i == 0, cr, sr, c, sn, a);
        }
        const float n_steps = static_cast<float>(steps);
        phase_finish_row<T>(n, 2.0f / n_steps, 1.0f / n_steps, p.offset_fraction, c, sn, a,
                            static_cast<T*>(nullptr));
        if (threshold != nullptr)
            modulated_threshold_row<T>(n, 1.0f / static_cast<float>(steps * carriers), raw, a,
                                       threshold);
        return;
    }
    case PhaseKind::micro: {
        const int others = static_cast<int>(p.micro_periods.size()) - 1;
        const T* in[18];
        for (int k = 0; k < p.frames; ++k) {
            in[k] = frame_at<T>(step.frame + k, offset);
            saturation_row(in[k], n, level, step.sat_bits, k == 0 && step.sat_first, sat);
        }
        MicroParams m;
        m.others = others;
        m.period = static_cast<float>(p.micro_periods[0]);
        m.offset = static_cast<float>(p.block.phase_offset);
        m.offset_fraction = p.offset_fraction;
        m.periods = p.micro_periods.data();
        m.first_order = p.first_order;
        m.orders = p.orders;
        m.order_cos = p.order_cos.data();
        m.order_sin = p.order_sin.data();
        m.highest = static_cast<float>(plan_.axes[p.axis].extent + 0.5);
        m.extra_offsets = p.micro_extra_offsets.data();
        m.min_gap = kMicroMinGap * full_scale_ * full_scale_;
        m.min_modulation = min_modulation_dn_;
        m.every_order = options_.micro_every_order;
        micro_base_row<T>(in, n, p.cos_w.data(), p.sin_w.data(), m, c, sn, a, scratch, span_);
        micro_search(n, m, c, sn, at(ps.ambiguous, offset, local), scratch, span_);
        return;
    }
    case PhaseKind::standard:
        break;
    }
}

template <class T>
FPP_VECTOR_CLONES void DecodeEngine::run_family_step(const Step& s, std::size_t offset, int n,
                                                     std::byte* local) const {
    switch (s.kind) {
    case StepKind::level_frame:
        copy_row<T>(frame_at<T>(s.frame, offset), n,
                    threshold_at<T>(s.index == 1 ? white_ : black_, offset, local));
        break;
    case StepKind::gray_digit: {
        const GrayInfo& g = plan_.grays[static_cast<std::size_t>(s.index)];
        if (g.threshold == GrayThreshold::phase_levels) {
            const PhaseState& ps = phase_state_[static_cast<std::size_t>(g.phase)];
            gray_digit_from_phase_row<T>(
                frame_at<T>(s.frame, offset), at(ps.mean, offset, local),
                at(ps.modulation, offset, local), n, static_cast<float>(g.block.levels - 1),
                g.weight[static_cast<std::size_t>(s.k)], s.first,
                at(code_[static_cast<std::size_t>(s.index)], offset, local));
            break;
        }
        gray_digit_row<T>(frame_at<T>(s.frame, offset), threshold_at<T>(white_, offset, local),
                          threshold_at<T>(black_, offset, local), n,
                          static_cast<float>(g.block.levels - 1),
                          g.weight[static_cast<std::size_t>(s.k)], s.first,
                          at(code_[static_cast<std::size_t>(s.index)], offset, local));
        if (g.phase < 0)
            doubt_digit_row<T>(frame_at<T>(s.frame, offset), threshold_at<T>(white_, offset, local),
                               threshold_at<T>(black_, offset, local), n,
                               static_cast<float>(g.block.levels - 1), min_modulation_dn_,
                               doubt_flag(g, s.k), s.first,
                               at(code_doubt_[static_cast<std::size_t>(s.index)], offset, local));
        break;
    }
    case StepKind::code_levels:
        code_levels_row<T>(threshold_at<T>(white_, offset, local),
                           threshold_at<T>(black_, offset, local), n,
                           at(code_modulation_[static_cast<std::size_t>(s.index)], offset, local),
                           at(code_mean_[static_cast<std::size_t>(s.index)], offset, local));
        break;
    default:
        break;
    }
}

template void DecodeEngine::run_family_block<std::uint8_t>(const Step&, std::size_t, int,
                                                           std::byte*, float*) const;
template void DecodeEngine::run_family_block<std::uint16_t>(const Step&, std::size_t, int,
                                                            std::byte*, float*) const;
template void DecodeEngine::run_family_step<std::uint8_t>(const Step&, std::size_t, int,
                                                          std::byte*) const;
template void DecodeEngine::run_family_step<std::uint16_t>(const Step&, std::size_t, int,
                                                           std::byte*) const;

} // namespace fpp::detail
