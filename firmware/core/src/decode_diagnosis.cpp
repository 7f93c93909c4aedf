#include "fpp/decode_diagnosis.hpp"

#include <algorithm>
#include <bit>
#include <cstdio>
#include <numeric>
#include <set>
#include <stdexcept>

namespace fpp {

namespace {

constexpr int kStep = 4;                // subsampling of the trials, both axes
constexpr double kNamedCoverage = 0.50; // a trial named must decode this much
constexpr double kNamedGain = 0.25;     // and this much more than the declared sequence

std::string percent(double fraction) {
    char text[32];
    std::snprintf(text, sizeof text, fraction < 0.1 ? "%.1f %%" : "%.0f %%", 100.0 * fraction);
    return text;
}

std::string block_field(std::size_t index) {
    return "sequence[" + std::to_string(index) + "]";
}

// Every kStep-th sample of `in` (width x height, rows contiguous) in x and y, << shift.
template <class T> Image<T> subsample(const T* in, Size size, int shift) {
    Image<T> out((size.width + kStep - 1) / kStep, (size.height + kStep - 1) / kStep);
    for (int y = 0; y < out.height(); ++y) {
        const T* row = in + std::size_t(y) * kStep * std::size_t(size.width);
        for (int x = 0; x < out.width(); ++x)
            out.at(x, y) = static_cast<T>(row[std::size_t(x) * kStep] << shift);
    }
    return out;
}

Frame subsample(const FrameView& in, int shift) {
    Frame out;
    out.bit_depth = in.bit_depth;
    out.significant_bits = in.significant_bits;
    if (in.bit_depth == 8)
        out.u8 = subsample(in.u8(), in.size, shift);
    else
        out.u16 = subsample(in.u16(), in.size, shift);
    return out;
}

int largest_sample(const std::vector<FrameView>& frames) {
    int largest = 0;
    for (const FrameView& f : frames) {
        const std::size_t n = f.empty() ? 0 : f.sample_count();
        if (f.bit_depth == 8)
            for (std::size_t i = 0; i < n; ++i)
                largest = std::max(largest, int(f.u8()[i]));
        else
            for (std::size_t i = 0; i < n; ++i)
                largest = std::max(largest, int(f.u16()[i]));
    }
    return largest;
}

struct Trials {
    const CaptureView& capture;
    const DecodeOptions& options;
    std::vector<std::uint8_t> lit; // of the subsampled pixels, from the declared decode
    std::size_t lit_count = 0;
    std::vector<int> first_frame; // per block
    std::set<std::vector<int>> orders_tried;
    std::vector<DecodeTrial> done;

    // Decodes the subsampled capture with `sequence`, frames in `order`, samples << shift.
    void run(std::string change, const Sequence& sequence, const std::vector<int>& order,
             int shift) {
        CaptureSet sub;
        sub.folder = capture.folder;
        sub.manifest = capture.manifest;
        sub.manifest.truth.reset();
        sub.manifest.sequence = sequence;
        sub.manifest.camera = {(capture.manifest.camera.width + kStep - 1) / kStep,
                               (capture.manifest.camera.height + kStep - 1) / kStep};
        for (const int source : order)
            sub.frames.push_back(
                subsample(capture.frames[static_cast<std::size_t>(source)], shift));
        double coverage = 0;
        try {
            const DecodeResult r = decode(sub, options);
            std::size_t decoded = 0;
            for (std::size_t i = 0; i < lit.size(); ++i)
                decoded += lit[i] && (r.mask.data()[i] & kDecodeValid);
            coverage = lit_count == 0 ? 0.0 : double(decoded) / double(lit_count);
        } catch (const std::exception&) {
            return; // a variant the decoder refuses is no explanation
        }
        done.push_back({std::move(change), coverage});
    }

    std::vector<int> identity() const {
        std::vector<int> order(capture.frames.size());
        std::iota(order.begin(), order.end(), 0);
        return order;
    }

    // A reordering of the frames, each tried once.
    void reorder(std::string change, const std::vector<int>& order) {
        if (order == identity() || !orders_tried.insert(order).second)
            return;
        run(std::move(change), capture.manifest.sequence, order, 0);
    }
};

void phase_block_trials(Trials& t, std::size_t index, const PhaseBlock& block) {
    const Sequence& declared = t.capture.manifest.sequence;
    Sequence flipped = declared;
    std::get<PhaseBlock>(flipped[index]).shift_sign = -block.shift_sign;
    t.run("shift_sign " + std::to_string(-block.shift_sign) + " in " + block_field(index), flipped,
          t.identity(), 0);

    const Size projector = t.capture.manifest.projector;
    const double extent = block.axis == Axis::x ? projector.width : projector.height;
    const double as_count = extent / block.period;
    if (as_count >= 2.0 && std::abs(as_count - block.period) > 0.5) {
        Sequence rescaled = declared;
        std::get<PhaseBlock>(rescaled[index]).period = as_count;
        char text[160];
        std::snprintf(text, sizeof text,
                      "period %.6g in %s (%.6g read as a fringe count across %.0f px)", as_count,
                      block_field(index).c_str(), block.period, extent);
        t.run(text, rescaled, t.identity(), 0);
    }

    if (block.shifting != PhaseShifting::standard)
        return;
    const int first = t.first_frame[index];
    const int n = block.steps;
    auto with = [&](auto&& place) {
        std::vector<int> order = t.identity();
        for (int k = 0; k < n; ++k)
            order[static_cast<std::size_t>(first + k)] = first + place(k);
        return order;
    };
    t.reorder("the frames of " + block_field(index) + " in reverse order",
              with([&](int k) { return n - 1 - k; }));
    for (int r = 1; r < n; ++r)
        t.reorder("the frames of " + block_field(index) + " rotated to start at its frame " +
                      std::to_string(r),
                  with([&](int k) { return (k + r) % n; }));
    for (int k = 0; k + 1 < n; ++k)
        t.reorder("frames " + std::to_string(first + k) + " and " + std::to_string(first + k + 1) +
                      " (in " + block_field(index) + ") swapped",
                  with([&](int j) { return j == k       ? k + 1
                                           : j == k + 1 ? k
                                                        : j; }));
}

void gray_block_trials(Trials& t, std::size_t index, const GrayBlock& block) {
    const int planes = block.bits + (block.complementary ? 1 : 0);
    if (planes < 2)
        return;
    const int per_plane = block.inverse ? 2 : 1;
    std::vector<int> order = t.identity();
    const int first = t.first_frame[index];
    for (int p = 0; p < planes; ++p)
        for (int f = 0; f < per_plane; ++f)
            order[static_cast<std::size_t>(first + p * per_plane + f)] =
                first + (planes - 1 - p) * per_plane + f;
    t.reorder("the code planes of " + block_field(index) + " in reverse order", order);
}

void sequence_trials(Trials& t) {
    const Sequence& declared = t.capture.manifest.sequence;
    std::vector<std::size_t> phase_blocks;
    for (std::size_t i = 0; i < declared.size(); ++i) {
        if (const auto* p = std::get_if<PhaseBlock>(&declared[i])) {
            phase_blocks.push_back(i);
            phase_block_trials(t, i, *p);
        } else if (const auto* g = std::get_if<GrayBlock>(&declared[i])) {
            gray_block_trials(t, i, *g);
        }
    }
    if (phase_blocks.size() > 1) {
        Sequence flipped = declared;
        for (const std::size_t i : phase_blocks) {
            auto& p = std::get<PhaseBlock>(flipped[i]);
            p.shift_sign = -p.shift_sign;
        }
        t.run("shift_sign flipped in every phase block", flipped, t.identity(), 0);
    }
    // Two phase blocks of one axis captured in each other's place.
    for (std::size_t a = 0; a < phase_blocks.size(); ++a)
        for (std::size_t b = a + 1; b < phase_blocks.size(); ++b) {
            const auto& pa = std::get<PhaseBlock>(declared[phase_blocks[a]]);
            const auto& pb = std::get<PhaseBlock>(declared[phase_blocks[b]]);
            const int n = frame_count(declared[phase_blocks[a]]);
            if (pa.axis != pb.axis || n != frame_count(declared[phase_blocks[b]]))
                continue;
            std::vector<int> order = t.identity();
            const int fa = t.first_frame[phase_blocks[a]], fb = t.first_frame[phase_blocks[b]];
            for (int k = 0; k < n; ++k)
                std::swap(order[std::size_t(fa + k)], order[std::size_t(fb + k)]);
            t.reorder("the frames of " + block_field(phase_blocks[a]) + " and " +
                          block_field(phase_blocks[b]) + " swapped",
                      order);
        }
}

const char* main_reason(const DecodeStatistics& s, std::size_t& count) {
    const std::pair<std::size_t, const char*> reasons[] = {
        {s.saturated, "saturated"},
        {s.low_modulation, "modulation below the decoder's minimum"},
        {s.unwrap_inconsistent, "code and phase disagree"},
        {s.out_of_range, "decoded outside the projector"},
        {s.no_cue, "no unwrapping cue"},
        {s.other, "not decoded, no flag"}};
    const auto* best =
        std::max_element(std::begin(reasons), std::end(reasons),
                         [](const auto& a, const auto& b) { return a.first < b.first; });
    count = best->first;
    return best->second;
}

} // namespace

double frames_full_scale(const CaptureSet& capture) {
    return frames_full_scale(view_of(capture));
}

DecodeDiagnosis diagnose_decode(const CaptureSet& capture, const DecodeResult& result,
                                const DecodeStatistics& stats, const DecodeOptions& options) {
    return diagnose_decode(view_of(capture), result, stats, options);
}

double frames_full_scale(const CaptureView& capture) {
    if (capture.frames.empty())
        return 255.0;
    const FrameView& first = capture.frames.front();
    if (first.bit_depth == 8 || first.significant_bits > 0)
        return double(first.max_value());
    const int bits = std::max(8, int(std::bit_width(unsigned(largest_sample(capture.frames)))));
    return double((1 << bits) - 1);
}

DecodeDiagnosis diagnose_decode(const CaptureView& capture, const DecodeResult& result,
                                const DecodeStatistics& stats, const DecodeOptions& options) {
    DecodeDiagnosis d;
    const bool nearly_nothing = nearly_nothing_decoded(stats);
    d.failed = nearly_nothing;
    if (!decode_suspect(stats) || capture.frames.empty())
        return d;

    // The decoder's full scale, against which its thresholds are set.
    const int full_scale = capture.frames.front().max_value();
    d.bits_declared = std::bit_width(static_cast<unsigned>(full_scale));
    d.bits_in_use = std::bit_width(static_cast<unsigned>(largest_sample(capture.frames)));

    Trials t{capture, options, {}, 0, {}, {}, {}};
    const Size sub = {(result.camera.width + kStep - 1) / kStep,
                      (result.camera.height + kStep - 1) / kStep};
    t.lit.resize(sub.area());
    const bool has_modulation = result.modulation.pixel_count() == result.mask.pixel_count();
    for (int y = 0; y < sub.height; ++y)
        for (int x = 0; x < sub.width; ++x) {
            const std::uint8_t m = result.mask.at(x * kStep, y * kStep);
            const bool lit = (m & (kDecodeValid | kDecodeSaturated)) != 0 || !has_modulation ||
                             double(result.modulation.at(x * kStep, y * kStep)) >= stats.lit_floor;
            t.lit[std::size_t(y) * std::size_t(sub.width) + std::size_t(x)] = lit ? 1 : 0;
            t.lit_count += lit ? 1 : 0;
        }
    int first = 0;
    for (const auto& block : capture.manifest.sequence) {
        t.first_frame.push_back(first);
        first += frame_count(block);
    }

    const int unused_bits = d.bits_declared - std::max(d.bits_in_use, 1);
    int bits_trial = -1;
    if (unused_bits >= 2) {
        bits_trial = static_cast<int>(t.done.size());
        t.run("samples scaled to " + std::to_string(d.bits_declared) + " bits",
              capture.manifest.sequence, t.identity(), unused_bits);
        if (t.done.empty())
            bits_trial = -1;
    }
    sequence_trials(t);
    d.trials = t.done;

    const double declared = stats.coverage_of_lit();
    for (std::size_t i = 0; i < d.trials.size(); ++i)
        if (d.trials[i].coverage_of_lit >= kNamedCoverage &&
            d.trials[i].coverage_of_lit >= declared + kNamedGain &&
            (d.best_trial < 0 ||
             d.trials[i].coverage_of_lit > d.trials[std::size_t(d.best_trial)].coverage_of_lit))
            d.best_trial = static_cast<int>(i);

    d.failed = nearly_nothing || d.best_trial >= 0;
    std::string m = (nearly_nothing ? "nearly nothing decoded: " : "only ") +
                    std::to_string(stats.decoded) + " of " + std::to_string(stats.lit) +
                    " lit pixels (" + percent(declared) + ")" + (nearly_nothing ? "" : " decoded") +
                    "; " + stats.floor_rule() + ". ";
    const bool few_bits = unused_bits >= 2;
    const bool bits_fix = bits_trial >= 0 && d.best_trial == bits_trial;
    if (few_bits) {
        const int largest = (1 << d.bits_in_use) - 1;
        m += "The frames use " + std::to_string(d.bits_in_use) + " of their " +
             std::to_string(d.bits_declared) + " bits (largest sample at most " +
             std::to_string(largest) + " of " + std::to_string(full_scale) + "): ";
        // Declaring the depth helps only where the samples, scaled to it,
        // decode: a set too dark for its noise stays too dark at any depth.
        if (capture.frames.front().bit_depth == 16 && bits_fix)
            m += "a " + std::to_string(std::max(d.bits_in_use, 9)) +
                 "-bit camera stored in 16 bits? Declare `bit_depth: " +
                 std::to_string(std::max(d.bits_in_use, 9)) +
                 "` in capture.yaml (or the camera's own depth, if higher)";
        else if (capture.frames.front().bit_depth == 16)
            m += "the frames are underexposed (scaled to full depth they decode no better, so "
                 "declaring a lower bit_depth would not help: expose longer or open the lens)";
        else
            m += "the frames are underexposed";
        if (bits_fix)
            m += "; scaled to full depth, " +
                 percent(d.trials[std::size_t(bits_trial)].coverage_of_lit) +
                 " of lit pixels decode instead of " + percent(declared) + ". ";
        else
            m += ". ";
    }
    if (d.best_trial >= 0 && !bits_fix) {
        const DecodeTrial& best = d.trials[std::size_t(d.best_trial)];
        m += "Likely cause: the capture's description. With " + best.change + ", " +
             percent(best.coverage_of_lit) + " of lit pixels decode instead of " +
             percent(declared) + " (measured on every 4th pixel).";
    } else if (d.best_trial < 0) {
        if (double(stats.lit) < kFailedLitFraction * double(stats.pixels)) {
            m += "Almost nothing is lit (" + std::to_string(stats.lit) + " of " +
                 std::to_string(stats.pixels) +
                 " pixels): the projector's light does not reach the camera, or the exposure is "
                 "far too short.";
        } else {
            std::size_t count = 0;
            const char* reason = main_reason(stats, count);
            m += "Most lit pixels were dropped as " + std::string(reason) + " (" +
                 std::to_string(count) + "). ";
            if (!d.trials.empty()) {
                const auto best = std::max_element(d.trials.begin(), d.trials.end(),
                                                   [](const DecodeTrial& a, const DecodeTrial& b) {
                                                       return a.coverage_of_lit < b.coverage_of_lit;
                                                   });
                m += "No reordering of the frames, flipped shift direction or period read as a "
                     "fringe count decodes much more (best: " +
                     best->change + ", " + percent(best->coverage_of_lit) + ").";
            }
        }
    }
    while (!m.empty() && m.back() == ' ')
        m.pop_back();
    d.message = m;
    return d;
}

} // namespace fpp
