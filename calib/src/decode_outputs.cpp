#include "decode_outputs.hpp"

#include "fpp/decode_accuracy.hpp"
#include "fpp/error.hpp"
#include "fpp/false_colour.hpp"
#include "fpp/image_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace fpp::calib {

namespace {

// The finest period of `axis`'s phase or micro phase blocks; for a
// code-only axis, its code step (the coordinate is the step's centre).
struct AxisResolution {
    double period = 0; // projector px
    bool code_only = false;
};

std::optional<AxisResolution> axis_resolution(const Sequence& sequence, Axis axis) {
    std::optional<double> finest, step;
    const auto keep = [](std::optional<double>& best, double v) {
        best = best ? std::min(*best, v) : v;
    };
    for (const auto& block : sequence) {
        if (const auto* phase = std::get_if<PhaseBlock>(&block); phase && phase->axis == axis)
            keep(finest, phase->period);
        if (const auto* micro = std::get_if<MicroPhaseBlock>(&block); micro && micro->axis == axis)
            for (const double p : micro->periods)
                keep(finest, p);
        if (const auto* code = std::get_if<GrayBlock>(&block); code && code->axis == axis)
            keep(step, code->complementary ? code->period / 2 : code->period);
    }
    if (finest)
        return AxisResolution{*finest, false};
    if (step)
        return AxisResolution{*step, true};
    return std::nullopt;
}

// 1st and 99th percentiles of the finite values, for a preview's colour range.
std::pair<float, float> robust_range(const Image<float>& values) {
    std::vector<float> finite;
    finite.reserve(values.pixel_count() / 16 + 1);
    const auto& v = values.storage();
    for (std::size_t i = 0; i < v.size(); i += 16)
        if (std::isfinite(v[i]))
            finite.push_back(v[i]);
    if (finite.empty())
        return {0.0f, 1.0f};
    std::sort(finite.begin(), finite.end());
    return {finite[finite.size() / 100], finite[finite.size() * 99 / 100]};
}

std::string fixed(double v, int digits) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", digits, v);
    return buf;
}

} // namespace

void write_decode_images(const std::filesystem::path& folder, const DecodeResult& result,
                         const CaptureManifest& manifest) {
    std::filesystem::create_directories(folder);
    if (!result.proj_x.empty()) {
        write_tiff(folder / "proj_x.tiff", result.proj_x);
        write_png(folder / "proj_x.png",
                  false_colour(result.proj_x, 0.0f, float(manifest.projector.width - 1)));
    }
    if (!result.proj_y.empty()) {
        write_tiff(folder / "proj_y.tiff", result.proj_y);
        write_png(folder / "proj_y.png",
                  false_colour(result.proj_y, 0.0f, float(manifest.projector.height - 1)));
    }
    write_tiff(folder / "modulation.tiff", result.modulation);
    const auto [lo, hi] = robust_range(result.modulation);
    write_png(folder / "modulation.png",
              false_colour(result.modulation, 0.0f, std::max(hi, lo + 1.0f)));

    Image<std::uint8_t> mask(result.camera, 1, 0);
    for (std::size_t i = 0; i < mask.pixel_count(); ++i)
        mask.data()[i] = (result.mask.data()[i] & kDecodeValid) ? 255 : 0;
    write_png(folder / "mask.png", mask);
    write_png(folder / "flags.png", result.mask);
}

std::string decode_statistics_text(const DecodeStatistics& s) {
    const auto share = [&](std::size_t n, std::size_t of) {
        return of == 0 ? std::string("-") : fixed(100.0 * double(n) / double(of), 2) + " %";
    };
    std::ostringstream md;
    md << "## Pixels\n\n";
    md << "A pixel is lit when its fringe modulation (the swing the patterns make in it, "
          "DN) is above the lit floor: it sees the projector. Dark pixels (shadow, "
          "background, a surface too dim for the exposure) are not counted against the "
          "coverage; decoded pixels are always lit.\n\n";
    md << "- lit: " << s.lit << " of " << s.pixels << " (" << share(s.lit, s.pixels) << "); "
       << s.floor_rule() << "\n";
    md << "- decoded: " << s.decoded << " of " << s.lit << " lit pixels (coverage of lit "
       << share(s.decoded, s.lit) << ")\n\n";
    md << "Why the others were dropped (each pixel counted once, in this order):\n\n";
    md << "| reason | pixels | of the image |\n|---|---|---|\n";
    const std::pair<const char*, std::size_t> rows[] = {
        {"dark (not lit)", s.dark},
        {"saturated", s.saturated},
        {"low modulation", s.low_modulation},
        {"code and phase disagree", s.unwrap_inconsistent},
        {"out of range (outside the projector)", s.out_of_range},
        {"no cue", s.no_cue},
        {"other (no flag)", s.other}};
    for (const auto& [name, n] : rows)
        md << "| " << name << " | " << n << " | " << share(n, s.pixels) << " |\n";
    return md.str();
}

std::string decode_summary(const DecodeResult& result, const CaptureSet& capture,
                           const DecodeStatistics& stats, const DecodeDiagnosis& diagnosis,
                           double decode_seconds) {
    const auto& m = capture.manifest;
    std::ostringstream md;
    md << "# Decode of " << capture.folder.filename().string() << "\n\n";
    md << "- camera " << m.camera.width << " x " << m.camera.height << ", projector "
       << m.projector.width << " x " << m.projector.height << ", " << m.frames.size() << " frames, "
       << (capture.frames.empty() ? 0 : capture.frames.front().bit_depth) << "-bit\n";
    std::size_t valid = 0;
    for (std::size_t i = 0; i < result.mask.pixel_count(); ++i)
        valid += (result.mask.data()[i] & kDecodeValid) != 0;
    md << "- decoded pixels: " << valid << " of " << result.mask.pixel_count() << " ("
       << fixed(100.0 * double(valid) / double(result.mask.pixel_count()), 2) << " %)\n";
    md << "- decode time: " << fixed(decode_seconds * 1000.0, 1) << " ms\n";
    if (!result.method_x.empty())
        md << "- x unwrapped by: " << result.method_x << "\n";
    if (!result.method_y.empty())
        md << "- y unwrapped by: " << result.method_y << "\n";
    for (const auto* c : {&result.phase_correction_x, &result.phase_correction_y})
        if (c->attempted)
            md << "- phase-error correction (" << (c == &result.phase_correction_x ? "x" : "y")
               << "): " << describe(*c) << "\n";
    md << "\n" << decode_statistics_text(stats);
    if (!diagnosis.message.empty()) {
        md << "\n## Diagnosis\n\n" << diagnosis.message << "\n";
        if (!diagnosis.trials.empty()) {
            md << "\nDecoded again on every 4th pixel in x and y with one change each "
                  "(coverage of the pixels lit above):\n\n| change | coverage of lit |\n"
                  "|---|---|\n";
            for (const auto& t : diagnosis.trials)
                md << "| " << t.change << " | " << fixed(100.0 * t.coverage_of_lit, 1) << " % |\n";
        }
    }

    if (!m.truth) {
        md << "\nNo ground truth in this capture set: no error figures.\n";
        return md.str();
    }
    const Image<float> truth = read_tiff_float(capture.folder / m.truth->projector);
    md << "\n## Error against ground truth (projector pixels)\n\n";
    md << "Error = decoded minus true projector coordinate of the surface point seen by the "
          "pixel centre. Unwrapping errors are pixels off by more than half the finest "
          "period (a code-only axis: more than its code step and half a pixel, past what "
          "its step alone puts a pixel off, about step / sqrt(12) RMS); RMS, mean and "
          "percentiles exclude them.\n\n";
    md << "| axis | period (or code step) | coverage | RMS | mean abs | p99 abs | max abs | "
          "unwrapping errors | decoded without light |\n";
    md << "|---|---|---|---|---|---|---|---|---|\n";
    for (int axis = 0; axis < 2; ++axis) {
        const Image<float>& decoded = axis == 0 ? result.proj_x : result.proj_y;
        const auto resolution = axis_resolution(m.sequence, axis == 0 ? Axis::x : Axis::y);
        if (decoded.empty() || !resolution)
            continue;
        // compare_to_truth counts errors beyond half its period as gross.
        const double compare_period =
            resolution->code_only ? 2.0 * (resolution->period + 0.5) : resolution->period;
        const AxisAccuracy a = compare_to_truth(decoded, truth, axis, compare_period);
        md << "| " << (axis == 0 ? "x" : "y") << " | " << fixed(resolution->period, 2)
           << (resolution->code_only ? " (code step)" : "") << " | "
           << fixed(100.0 * a.coverage(), 2) << " % | " << fixed(a.rms_px, 4) << " | "
           << fixed(a.mean_abs_px, 4) << " | " << fixed(a.p99_abs_px, 4) << " | "
           << fixed(a.max_abs_px, 4) << " | " << a.unwrap_errors << " ("
           << fixed(100.0 * a.unwrap_error_rate(), 4) << " %) | " << a.false_valid << " |\n";
    }
    return md.str();
}

std::string consistency_text(const DecodeConsistency& consistency) {
    std::ostringstream md;
    md << "\n## Consistency\n\n";
    md << "Along each checked axis (a phase joined to a cue), on the pixels whose row (x) or "
          "column (y) steps smoothly: the share stepping against the coordinate's own trend "
          "(a reversed shift) and the jumps of half or a whole period between smooth sides, "
          "per period travelled (a wrong phase or code offset); a correct description leaves "
          "about none of either (fpp/decode_consistency.hpp).\n\n";
    md << "| axis | smooth pixels | against the trend | jumps per period |\n|---|---|---|---|\n";
    bool any = false;
    for (int axis = 0; axis < 2; ++axis) {
        const AxisConsistency& a = consistency.axis[axis];
        if (!a.checked)
            continue;
        any = true;
        md << "| " << (axis == 0 ? "x" : "y") << " | " << a.smooth << " | "
           << fixed(100.0 * a.against_fraction(), 3) << " % | " << fixed(a.jumps_per_period(), 3)
           << " |\n";
    }
    if (!any)
        md << "| - | (no axis joins a phase to a cue: nothing to check) | | |\n";
    md << "\n"
       << (consistency.inconsistent ? "Inconsistent: " + consistency.message
                                    : std::string("Consistent."))
       << "\n";
    return md.str();
}

std::string decode_summary(const DecodeResult& result, const CaptureSet& capture,
                           double decode_seconds) {
    const DecodeStatistics stats = decode_statistics(result, frames_full_scale(capture));
    return decode_summary(result, capture, stats, diagnose_decode(capture, result, stats, {}),
                          decode_seconds);
}

} // namespace fpp::calib
