#include "fpp/decode_report.hpp"

#include "fpp/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace fpp {

namespace {

constexpr int kBins = 256; // over [0, full_scale / 8)
constexpr double kBinFraction = 1.0 / 2048.0;
constexpr double kMaxDarkMode = 1.0 / 64.0; // of full scale
constexpr double kFloorSigmas = 5.0;
constexpr double kMinFloor = 1.0 / 256.0; // of full scale: one step of 8-bit data
constexpr double kFallbackFloor = 0.01;   // of full scale

struct Floor {
    double dn = 0;
    double sigma = 0;
    bool dark_mode = false;
};

// The rule of decode_report.hpp: 5 sigma above the dark mode, or 1 % of full scale.
Floor find_floor(const Image<float>& modulation, double full_scale) {
    const double bin = full_scale * kBinFraction;
    std::vector<double> histogram(kBins, 0.0);
    for (const float b : modulation.storage()) {
        // NaN, and exact zeros: every frame equal (clipped at black), no noise to measure.
        if (!(b > 0.0f))
            continue;
        const double index = double(b) / bin;
        if (index < double(kBins))
            histogram[static_cast<std::size_t>(index)] += 1.0;
    }
    // Box-smoothed over 5 bins (quantised 8-bit modulation is spiky).
    std::vector<double> smooth(kBins, 0.0);
    for (int i = 0; i < kBins; ++i) {
        double sum = 0;
        int n = 0;
        for (int j = std::max(0, i - 2); j <= std::min(kBins - 1, i + 2); ++j, ++n)
            sum += histogram[static_cast<std::size_t>(j)];
        smooth[static_cast<std::size_t>(i)] = sum / double(n);
    }
    const int last_mode_bin = static_cast<int>(kMaxDarkMode / kBinFraction); // 32
    int mode = 0;
    for (int i = 1; i <= last_mode_bin; ++i)
        if (smooth[static_cast<std::size_t>(i)] > smooth[static_cast<std::size_t>(mode)])
            mode = i;
    const double peak = smooth[static_cast<std::size_t>(mode)];
    const double mode_dn = (mode + 0.5) * bin;
    // A peak, not the rising edge of the lit pixels: half its height by 3 x its position.
    const int fall_by =
        std::min(kBins - 1, std::max(mode + 4, static_cast<int>(3.0 * mode_dn / bin)));
    bool falls = false;
    for (int i = mode + 1; i <= fall_by; ++i)
        falls = falls || smooth[static_cast<std::size_t>(i)] <= 0.5 * peak;
    // And rising from zero as a Rayleigh density does (at half its mode it is
    // 0.73 of the peak): not the lower edge of the lit pixels' modulation.
    const bool from_zero = mode < 4 || smooth[static_cast<std::size_t>(mode / 2)] >= 0.3 * peak;
    Floor f;
    if (peak > 0 && falls && from_zero) {
        f.dark_mode = true;
        f.sigma = mode_dn;
        f.dn = std::max(kFloorSigmas * mode_dn, kMinFloor * full_scale);
    } else {
        f.dn = kFallbackFloor * full_scale;
    }
    return f;
}

} // namespace

double DecodeStatistics::coverage_of_lit() const {
    return lit == 0 ? 0.0 : double(decoded) / double(lit);
}

std::size_t DecodeStatistics::counted() const {
    return decoded + dark + saturated + low_modulation + unwrap_inconsistent + out_of_range +
           no_cue + other;
}

std::string DecodeStatistics::floor_rule() const {
    char text[200];
    if (floor_from_dark_mode)
        std::snprintf(text, sizeof text,
                      "lit floor %.3g DN (5 sigma of the dark pixels' modulation, sigma %.3g DN)",
                      lit_floor, dark_sigma);
    else
        std::snprintf(text, sizeof text,
                      "lit floor %.3g DN (1 %% of full scale %.0f DN: the modulation of the "
                      "pixels below it shows no noise peak to set the floor from)",
                      lit_floor, full_scale);
    return text;
}

namespace {

// Counts `mask` by the precedence of decode_report.hpp; lit(i) says whether
// pixel i, not decoded and not saturated, is lit.
template <class Lit>
void count_pixels(const Image<std::uint8_t>& mask, Lit&& lit, DecodeStatistics& s) {
    s.pixels = mask.pixel_count();
    const std::uint8_t* flags = mask.data();
    for (std::size_t i = 0; i < s.pixels; ++i) {
        const std::uint8_t m = flags[i];
        if (m & kDecodeValid) {
            ++s.decoded;
            ++s.lit;
            continue;
        }
        const bool saturated = (m & kDecodeSaturated) != 0;
        if (!saturated && !lit(i)) {
            ++s.dark;
            continue;
        }
        ++s.lit;
        if (saturated)
            ++s.saturated;
        else if (m & kDecodeLowModulation)
            ++s.low_modulation;
        else if (m & kDecodeUnwrapInconsistent)
            ++s.unwrap_inconsistent;
        else if (m & kDecodeOutOfRange)
            ++s.out_of_range;
        else if (m & kDecodeNoCue)
            ++s.no_cue;
        else
            ++s.other;
    }
}

void check_arguments(const DecodeResult& result, double full_scale) {
    if (!(full_scale > 0))
        throw InputError("decode_statistics", "full_scale", "full scale must be > 0 DN");
    if (result.mask.empty())
        throw InputError("decode_statistics", "mask", "the decode result has no mask");
}

} // namespace

DecodeStatistics decode_statistics(const DecodeResult& result, double full_scale) {
    check_arguments(result, full_scale);
    DecodeStatistics s;
    s.full_scale = full_scale;
    if (result.modulation.pixel_count() != result.mask.pixel_count()) {
        count_pixels(
            result.mask, [](std::size_t) { return true; }, s);
        return s;
    }
    const Floor f = find_floor(result.modulation, full_scale);
    s.lit_floor = f.dn;
    s.dark_sigma = f.sigma;
    s.floor_from_dark_mode = f.dark_mode;
    const auto floor = static_cast<float>(s.lit_floor);
    const float* modulation = result.modulation.data();
    count_pixels(
        result.mask, [&](std::size_t i) { return modulation[i] >= floor; }, s);
    return s;
}

DecodeStatistics fused_decode_statistics(const DecodeResult& fused,
                                         const std::vector<const DecodeResult*>& passes,
                                         double full_scale) {
    check_arguments(fused, full_scale);
    std::vector<DecodeStatistics> each;
    for (std::size_t i = 0; i < passes.size(); ++i) {
        const DecodeResult* pass = passes[i];
        if (pass == nullptr || pass->mask.size() != fused.mask.size())
            throw InputError("fused_decode_statistics", "passes[" + std::to_string(i) + "]",
                             "a pass of another size");
        each.push_back(decode_statistics(*pass, full_scale));
    }
    DecodeStatistics s;
    s.full_scale = full_scale;
    if (!each.empty()) {
        s.lit_floor = each.front().lit_floor;
        s.dark_sigma = each.front().dark_sigma;
        s.floor_from_dark_mode = each.front().floor_from_dark_mode;
    }
    count_pixels(
        fused.mask,
        [&](std::size_t i) {
            for (std::size_t k = 0; k < passes.size(); ++k) {
                const DecodeResult& r = *passes[k];
                if (r.modulation.pixel_count() != r.mask.pixel_count() ||
                    r.modulation.data()[i] >= static_cast<float>(each[k].lit_floor))
                    return true;
            }
            return passes.empty();
        },
        s);
    return s;
}

bool nearly_nothing_decoded(const DecodeStatistics& stats) {
    return stats.coverage_of_lit() < kFailedCoverageOfLit ||
           double(stats.lit) < kFailedLitFraction * double(stats.pixels);
}

bool decode_suspect(const DecodeStatistics& stats) {
    return nearly_nothing_decoded(stats) || stats.coverage_of_lit() < kSuspectCoverageOfLit;
}

} // namespace fpp
