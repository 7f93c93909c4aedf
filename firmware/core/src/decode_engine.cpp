#include "decode_engine.hpp"

#include "decode_family_kernels.hpp"
#include "decode_kernels.hpp"
#include "decode_micro.hpp"
#include "unwrap_spatial.hpp"
#include "unwrap_temporal.hpp"

#include "fpp/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

FPP_NO_FP_CONTRACT

namespace fpp::detail {

namespace {

constexpr std::size_t kAlign = 64;
constexpr int kMaxBlocksPerAxis = 16;
// Pixels per span. A batch span's state (fraction, code, thresholds,
// saturation: about 40 bytes per pixel with the frames' samples) stays in the
// L2 cache while it goes through every step, and each frame is read in runs
// long enough for the hardware prefetchers (4096 measured faster than 1024 or
// 2048 on the benchmark machine, about the same as 8192).
constexpr std::size_t kSpanPixels = 4096;
constexpr std::size_t kCacheLine = 64;

// The modulation floor as an integer bound on a difference of samples:
// d < x is d < ceil(x) for integer d.
std::int32_t ceil_dn(float x) {
    return static_cast<std::int32_t>(std::ceil(x));
}

// The doubt plane of a code-only axis's thresholded plane (white and black
// are read only for the planes doubt_against_levels names).
template <class T>
FPP_KERNEL void code_doubt_row(const GrayInfo& g, const T* in, const T* threshold, const T* white,
                               const T* black, int n, float min_modulation_dn, std::uint16_t flag,
                               bool first, std::uint16_t* doubt) {
    if (doubt_against_levels(g, flag))
        doubt_levels_row(in, threshold, white, black, n, ceil_dn(min_modulation_dn), flag, first,
                         doubt);
    else
        doubt_threshold_row(in, threshold, n, ceil_dn(min_modulation_dn), flag, first, doubt);
}

std::uint8_t axis_bit(int axis) {
    return static_cast<std::uint8_t>(1u << axis);
}

} // namespace

DecodeEngine::DecodeEngine(Plan plan, const DecodeOptions& options, Mode mode,
                           DecodeResult* recycled)
    : plan_(std::move(plan)), options_(options), mode_(mode),
      pool_(ThreadPool::shared(options.threads)) {
    width_ = plan_.camera.width;
    height_ = plan_.camera.height;
    area_ = plan_.camera.area();
    full_ = mode_ == Mode::streaming || plan_.needs_full_storage;
    span_ = static_cast<int>(std::min<std::size_t>(kSpanPixels, std::max<std::size_t>(area_, 1)));
    for (int a = 0; a < 2; ++a)
        constants_[a] = axis_constants(plan_, a);
    if (!options_.saturation_in_binary_frames)
        for (Step& s : plan_.steps)
            if (s.kind != StepKind::phase_block)
                s.sat_bits = 0;
    single_decider_ = (plan_.axes[0].coded != plan_.axes[1].coded) && !plan_.needs_full_storage;

    for (int a = 0; a < 2; ++a)
        if (plan_.axes[a].phases.size() > static_cast<std::size_t>(kMaxBlocksPerAxis))
            refuse_sequence(plan_, "sequence",
                            "more than 16 phase blocks on axis " + std::string(a == 0 ? "x" : "y"));

    allocate_result(recycled);
    const int report_axis = plan_.axes[0].coded ? 0 : 1;
    const int report = plan_.axes[report_axis].report_phase;

    phase_state_.resize(plan_.phases.size());
    for (std::size_t b = 0; b < plan_.phases.size(); ++b) {
        if (!plan_.phases[b].used)
            continue;
        PhaseState& ps = phase_state_[b];
        ps.fraction = make_plane(float_store_, full_);
        // The reported block's B and A are the result's images.
        if (static_cast<int>(b) != report) {
            ps.modulation = make_plane(float_store_, full_);
            ps.mean = make_plane(float_store_, full_);
        }
        if (plan_.phases[b].thresholds)
            ps.threshold = make_plane(u16_store_, full_);
        const PhaseInfo& info = plan_.phases[b];
        if (info.kind == PhaseKind::micro) {
            ps.ambiguous = make_plane(u8_store_, full_);
            scratch_floats_ =
                std::max(scratch_floats_,
                         micro_scratch_floats(static_cast<int>(info.micro_periods.size()) - 1));
        }
        if (info.kind == PhaseKind::modulated)
            scratch_floats_ = std::max(scratch_floats_, 3);
    }
    code_.resize(plan_.grays.size());
    code_modulation_.resize(plan_.grays.size());
    code_mean_.resize(plan_.grays.size());
    code_doubt_.resize(plan_.grays.size());
    for (std::size_t g = 0; g < plan_.grays.size(); ++g) {
        code_[g] = make_plane(u16_store_, full_);
        if (plan_.grays[g].phase < 0)
            code_doubt_[g] = make_plane(u16_store_, full_);
        if (plan_.grays[g].phase < 0 &&
            static_cast<int>(g) != plan_.axes[report_axis].gray) { // reported: result images
            code_modulation_[g] = make_plane(float_store_, full_);
            code_mean_[g] = make_plane(float_store_, full_);
        }
    }
    bind_report_planes();
    if (plan_.uses_levels) {
        white_ = make_plane(u16_store_, full_);
        black_ = make_plane(u16_store_, full_);
    }
    for (int w = 0; scratch_floats_ > 0 && w < pool_.size(); ++w)
        scratch_.push_back(std::make_unique_for_overwrite<float[]>(
            static_cast<std::size_t>(scratch_floats_) * static_cast<std::size_t>(span_)));
    line_.resize(plan_.centerlines.size());
    for (std::size_t c = 0; c < plan_.centerlines.size(); ++c)
        if (plan_.centerlines[c].phase >= 0)
            line_[c] = make_plane(u8_store_, full_);
    if (plan_.uses_white_black)
        white_black_ = make_plane(u16_store_, full_);
    sat_ = make_plane(u8_store_, full_);

    for (int a = 0; a < 2; ++a) {
        const AxisPlan& ap = plan_.axes[a];
        if (!ap.coded)
            continue;
        if (ap.method == UnwrapMethod::gray &&
            !plan_.grays[static_cast<std::size_t>(ap.gray)].block.complementary) {
            gray_estimate_[a] = make_plane(float_store_, true).full;
            gray_edge_[a] = make_plane(u8_store_, true).full;
        }
        if (ap.method == UnwrapMethod::centerline && region_ == nullptr) {
            i32_store_.push_back(std::make_unique_for_overwrite<std::int32_t[]>(area_));
            region_ = i32_store_.back().get();
            i32_store_.push_back(std::make_unique_for_overwrite<std::int32_t[]>(area_));
            queue_next_ = i32_store_.back().get();
        }
    }
    if (!full_)
        for (int w = 0; w < pool_.size(); ++w)
            local_spans_.push_back(
                std::make_unique_for_overwrite<std::byte[]>(local_bytes_ + kAlign));

    frame_base_.assign(static_cast<std::size_t>(plan_.frame_count), nullptr);
    if (mode_ == Mode::batch)
        build_batch_groups();
    else
        build_streaming_work();
}

void DecodeEngine::build_streaming_work() {
    // A phase block's slices run after steps triggered later on some spans;
    // the results are the same because those steps neither read its planes
    // (the plan ends its slices before any step that does) nor assign the
    // saturation bytes (only the first writer assigns, and all OR).
    const int spans = span_count();
    work_.assign(static_cast<std::size_t>(plan_.frame_count), {});
    for (std::size_t i = 0; i < plan_.steps.size(); ++i) {
        Step& s = plan_.steps[i];
        const int parts = s.kind == StepKind::phase_block ? s.parts : 1;
        for (int p = 0; p < parts; ++p)
            work_[static_cast<std::size_t>(s.trigger + p)].push_back(
                {static_cast<int>(i), p * spans / parts, (p + 1) * spans / parts});
        if (parts > 1 && s.sat_first) {
            s.sat_first = false;
            clear_sat_at_ = s.trigger;
        }
    }
}

void DecodeEngine::build_batch_groups() {
    // The plan's order, with runs of gray planes of one block thresholded
    // against one image grouped (up to four planes per pass).
    for (const Step& s : plan_.steps) {
        if (s.kind == StepKind::gray_threshold && !batch_groups_.empty()) {
            BatchGroup& last = batch_groups_.back();
            const Step& prev = plan_.steps[static_cast<std::size_t>(last.first + last.count - 1)];
            if (last.kind == GroupKind::gray_planes && last.count < 4 && prev.index == s.index &&
                prev.k + 1 == s.k) {
                ++last.count;
                continue;
            }
        }
        BatchGroup group;
        group.first = static_cast<int>(&s - plan_.steps.data());
        group.kind =
            s.kind == StepKind::gray_threshold ? GroupKind::gray_planes : GroupKind::single;
        batch_groups_.push_back(group);
    }
    // Frames read by steps after the first, and not by the first.
    std::vector<char> wanted(static_cast<std::size_t>(plan_.frame_count), 0);
    for (std::size_t i = 1; i < plan_.steps.size(); ++i) {
        const Step& s = plan_.steps[i];
        for (int f = 0; s.frame >= 0 && f < s.frames; ++f)
            wanted[static_cast<std::size_t>(s.frame + f)] = 1;
        if (s.frame2 >= 0)
            wanted[static_cast<std::size_t>(s.frame2)] = 1;
    }
    if (!plan_.steps.empty()) {
        const Step& head = plan_.steps.front();
        for (int f = 0; head.frame >= 0 && f < head.frames; ++f)
            wanted[static_cast<std::size_t>(head.frame + f)] = 0;
    }
    for (int f = 0; f < plan_.frame_count; ++f)
        if (wanted[static_cast<std::size_t>(f)] != 0)
            prefetch_frames_.push_back(f);
}

template <class T>
PlaneRef<T> DecodeEngine::make_plane(std::vector<std::unique_ptr<T[]>>& store, bool full) {
    PlaneRef<T> p;
    if (full) {
        store.push_back(std::make_unique_for_overwrite<T[]>(area_));
        p.full = store.back().get();
    } else {
        local_bytes_ = (local_bytes_ + kAlign - 1) / kAlign * kAlign;
        p.local = local_bytes_;
        local_bytes_ += static_cast<std::size_t>(span_) * sizeof(T);
    }
    return p;
}

float* DecodeEngine::scratch_buffer(int worker) const {
    return scratch_.empty() ? nullptr : scratch_[static_cast<std::size_t>(worker)].get();
}

std::byte* DecodeEngine::local_buffer(int worker) const {
    if (local_spans_.empty())
        return nullptr;
    std::byte* base = local_spans_[static_cast<std::size_t>(worker)].get();
    const auto addr = reinterpret_cast<std::uintptr_t>(base);
    return base + ((kAlign - addr % kAlign) % kAlign);
}

int DecodeEngine::span_count() const {
    return static_cast<int>((area_ + static_cast<std::size_t>(span_) - 1) /
                            static_cast<std::size_t>(span_));
}

template <class F> void DecodeEngine::for_spans(int spans_per_task, F&& fn) {
    pool_.parallel_for(span_count(), spans_per_task, [&](int b, int e, int worker) {
        for (int i = b; i < e; ++i) {
            const std::size_t offset =
                static_cast<std::size_t>(i) * static_cast<std::size_t>(span_);
            fn(offset,
               static_cast<int>(
                   std::min<std::size_t>(static_cast<std::size_t>(span_), area_ - offset)),
               worker);
        }
    });
}

void DecodeEngine::allocate_result(DecodeResult* recycled) {
    // Images of a previous result are reused when their size fits; fresh ones
    // are zero-filled by Image, so build them on all threads at once.
    const Size size = plan_.camera;
    auto fits = [&](const auto& img) { return img.size() == size && img.channels() == 1; };
    result_.camera = size;
    std::vector<Image<float>*> fresh;
    bool fresh_mask = true;
    auto adopt = [&](Image<float>& mine, Image<float>* old) {
        if (old != nullptr && fits(*old))
            mine = std::move(*old);
        else
            fresh.push_back(&mine);
    };
    adopt(result_.modulation, recycled != nullptr ? &recycled->modulation : nullptr);
    adopt(result_.mean, recycled != nullptr ? &recycled->mean : nullptr);
    for (int a = 0; a < 2; ++a) {
        if (!plan_.axes[a].coded)
            continue;
        Image<float>* old = nullptr;
        if (recycled != nullptr)
            old = a == 0 ? &recycled->proj_x : &recycled->proj_y;
        // A recycled image of the other axis is as good.
        if (recycled != nullptr && (old->empty() || !fits(*old)))
            old = a == 0 ? &recycled->proj_y : &recycled->proj_x;
        adopt(a == 0 ? result_.proj_x : result_.proj_y, old);
    }
    if (recycled != nullptr && fits(recycled->mask)) {
        result_.mask = std::move(recycled->mask);
        fresh_mask = false;
    }
    const int jobs = static_cast<int>(fresh.size()) + (fresh_mask ? 1 : 0);
    pool_.parallel_for(jobs, 1, [&](int b, int e, int) {
        for (int j = b; j < e; ++j) {
            if (j < static_cast<int>(fresh.size()))
                *fresh[static_cast<std::size_t>(j)] = Image<float>(size);
            else
                result_.mask = Image<std::uint8_t>(size);
        }
    });
    for (int a = 0; a < 2; ++a) {
        if (!plan_.axes[a].coded)
            continue;
        proj_[a] = (a == 0 ? result_.proj_x : result_.proj_y).data();
        (a == 0 ? result_.method_x : result_.method_y) = plan_.axes[a].name;
    }
}

void DecodeEngine::bind_report_planes() {
    const int report_axis = plan_.axes[0].coded ? 0 : 1;
    const int report = plan_.axes[report_axis].report_phase;
    if (plan_.axes[report_axis].method == UnwrapMethod::code) {
        const auto g = static_cast<std::size_t>(plan_.axes[report_axis].gray);
        code_modulation_[g].full = result_.modulation.data();
        code_mean_[g].full = result_.mean.data();
        return;
    }
    if (report < 0)
        return;
    PhaseState& ps = phase_state_[static_cast<std::size_t>(report)];
    ps.modulation.full = result_.modulation.data();
    ps.mean.full = result_.mean.data();
}

void DecodeEngine::restart(DecodeResult* recycled) {
    if (mode_ != Mode::streaming)
        throw std::logic_error("restart() on a batch decoder");
    // An unfinished sequence still holds its result images: they are reused.
    DecodeResult held = std::move(result_);
    allocate_result(finished_ ? recycled : &held);
    bind_report_planes();
    std::fill(frame_base_.begin(), frame_base_.end(), nullptr);
    received_ = 0;
    depth_ = 0;
    finished_ = false;
}

void DecodeEngine::check_frame(const FrameView& frame, int index) const {
    // Named as the capture-set reader names a frame: field "frames[i]".
    const std::string field = "frames[" + std::to_string(index) + "]";
    const std::string where = "frame " + std::to_string(index) + ": ";
    auto refuse = [&](const std::string& what) {
        throw InputError(plan_.origin, field, where + what);
    };
    if (frame.bit_depth != 8 && frame.bit_depth != 16)
        refuse("bit depth must be 8 or 16, got " + std::to_string(frame.bit_depth));
    if (frame.empty())
        refuse("no pixel data for its bit depth");
    if (frame.channels != 1)
        refuse("must have one channel");
    if (frame.size != plan_.camera)
        refuse("size " + std::to_string(frame.size.width) + "x" +
               std::to_string(frame.size.height) + " differs from the camera size " +
               std::to_string(plan_.camera.width) + "x" + std::to_string(plan_.camera.height));
    if (depth_ != 0 && frame.bit_depth != depth_)
        refuse("bit depth " + std::to_string(frame.bit_depth) + " differs from the first frame's " +
               std::to_string(depth_));
}

void DecodeEngine::set_depth(const FrameView& first) {
    depth_ = first.bit_depth;
    // The bits in use, not the container's: a 12-bit camera in 16-bit frames
    // saturates at 4095 and its modulation floor scales with 4095.
    const double full_scale = static_cast<double>(first.max_value());
    const double level = std::clamp(std::ceil(options_.saturation * full_scale), 0.0, full_scale);
    sat_level_ = static_cast<std::uint16_t>(level);
    min_modulation_dn_ = static_cast<float>(options_.min_modulation * full_scale);
    full_scale_ = static_cast<float>(full_scale);
}

template <class T>
FPP_VECTOR_CLONES void DecodeEngine::run_step(const Step& s, std::size_t offset, int n,
                                              std::byte* local, float* scratch) const {
    const T* in = s.frame >= 0 ? frame_at<T>(s.frame, offset) : nullptr;
    const T level = static_cast<T>(sat_level_);
    std::uint8_t* sat = at(sat_, offset, local);
    if (s.kind == StepKind::phase_block) {
        run_phase_block<T>(s, offset, n, local, scratch);
        return;
    }
    if (in != nullptr && (s.sat_bits != 0 || s.sat_first))
        saturation_row(in, n, level, s.sat_bits, s.sat_first, sat);
    switch (s.kind) {
    case StepKind::white_black_frame:
        white_black_row(in, n, s.first, threshold_at<T>(white_black_, offset, local));
        break;
    case StepKind::gray_threshold: {
        const GrayInfo& g = plan_.grays[static_cast<std::size_t>(s.index)];
        const std::uint16_t bit = g.weight[static_cast<std::size_t>(s.k)];
        const T* threshold =
            g.threshold == GrayThreshold::white_black
                ? threshold_at<T>(white_black_, offset, local)
                : threshold_at<T>(phase_state_[static_cast<std::size_t>(g.phase)].threshold, offset,
                                  local);
        gray_planes_row<T, 1>(&in, n, threshold, &bit, s.first,
                              at(code_[static_cast<std::size_t>(s.index)], offset, local));
        if (g.phase < 0)
            code_doubt_row(g, in, threshold, threshold_at<T>(white_, offset, local),
                           threshold_at<T>(black_, offset, local), n, min_modulation_dn_,
                           doubt_flag(g, s.k), s.first,
                           at(code_doubt_[static_cast<std::size_t>(s.index)], offset, local));
        break;
    }
    case StepKind::gray_inverse: {
        const GrayInfo& g = plan_.grays[static_cast<std::size_t>(s.index)];
        const T* inverse = frame_at<T>(s.frame2, offset);
        if (s.sat_bits != 0)
            saturation_row(inverse, n, level, s.sat_bits, false, sat);
        const std::uint16_t bit = g.weight[static_cast<std::size_t>(s.k)];
        const auto gi = static_cast<std::size_t>(s.index);
        if (g.phase < 0)
            code_inverse_plane_row(
                in, inverse, n, bit, ceil_dn(2.0f * min_modulation_dn_), doubt_flag(g, s.k),
                s.first, at(code_[gi], offset, local), at(code_doubt_[gi], offset, local),
                at(code_modulation_[gi], offset, local), at(code_mean_[gi], offset, local));
        else
            gray_inverse_row(in, inverse, n, bit, s.first, at(code_[gi], offset, local));
        break;
    }
    case StepKind::centerline_bit: {
        const CenterlineInfo& c = plan_.centerlines[static_cast<std::size_t>(s.index)];
        centerline_row(in, n,
                       threshold_at<T>(phase_state_[static_cast<std::size_t>(c.phase)].threshold,
                                       offset, local),
                       at(line_[static_cast<std::size_t>(s.index)], offset, local));
        break;
    }
    default:
        run_family_step<T>(s, offset, n, local);
        break;
    }
}

namespace {

// phase_block_classes for the block's N, compiled for each N up to
// kMaxClassSteps.
template <class T, int N>
FPP_KERNEL void phase_block_classes_any(int steps, const T* const* in, int n, const float* cw,
                                        const float* sw, T level, const SatUpdate& sat, float* c,
                                        float* s, float* a) {
    if constexpr (N <= kMaxClassSteps) {
        if (steps == N)
            phase_block_classes<T, N>(in, n, cw, sw, level, sat, c, s, a);
        else
            phase_block_classes_any<T, N + 1>(steps, in, n, cw, sw, level, sat, c, s, a);
    }
}

} // namespace

template <class T>
FPP_VECTOR_CLONES void DecodeEngine::run_phase_block(const Step& step, std::size_t offset, int n,
                                                     std::byte* local, float* scratch) const {
    const PhaseInfo& p = plan_.phases[static_cast<std::size_t>(step.index)];
    if (p.kind != PhaseKind::standard) {
        run_family_block<T>(step, offset, n, local, scratch);
        return;
    }
    const PhaseState& ps = phase_state_[static_cast<std::size_t>(step.index)];
    float* c = at(ps.fraction, offset, local);
    float* sn = at(ps.modulation, offset, local);
    float* a = at(ps.mean, offset, local);
    const T level = static_cast<T>(sat_level_);
    const int steps = p.block.steps;
    SatUpdate update{at(sat_, offset, local), step.sat_bits,
                     step.sat_first ? std::uint8_t{0} : std::uint8_t{0xff}};
    if (steps <= kMaxClassSteps) {
        const T* in[kMaxClassSteps];
        for (int k = 0; k < steps; ++k)
            in[k] = frame_at<T>(step.frame + k, offset);
        phase_block_classes_any<T, 3>(steps, in, n, p.class_cos_w.data(), p.class_sin_w.data(),
                                      level, update, c, sn, a);
    } else {
        // Frames four at a time, in order k = 0 .. N-1, the sums staying in
        // registers within a run of four.
        for (int k = 0; k < steps; k += 4) {
            const T* in[4] = {nullptr, nullptr, nullptr, nullptr};
            const int g = std::min(4, steps - k);
            for (int j = 0; j < g; ++j)
                in[j] = frame_at<T>(step.frame + k + j, offset);
            if (k > 0)
                update.keep = 0xff;
            const float* cw = p.cos_w.data() + k;
            const float* sw = p.sin_w.data() + k;
            switch (g) {
            case 1:
                phase_frames_row<T, 1>(in, n, cw, sw, k == 0, level, update, c, sn, a);
                break;
            case 2:
                phase_frames_row<T, 2>(in, n, cw, sw, k == 0, level, update, c, sn, a);
                break;
            case 3:
                phase_frames_row<T, 3>(in, n, cw, sw, k == 0, level, update, c, sn, a);
                break;
            default:
                phase_frames_row<T, 4>(in, n, cw, sw, k == 0, level, update, c, sn, a);
                break;
            }
        }
    }
    const float n_steps = static_cast<float>(steps);
    phase_finish_row<T>(n, 2.0f / n_steps, 1.0f / n_steps, p.offset_fraction, c, sn, a,
                        p.thresholds ? threshold_at<T>(ps.threshold, offset, local) : nullptr);
}

template <class T>
FPP_VECTOR_CLONES void DecodeEngine::run_gray_planes(const BatchGroup& group, std::size_t offset,
                                                     int n, std::byte* local) const {
    const Step& head = plan_.steps[static_cast<std::size_t>(group.first)];
    const GrayInfo& g = plan_.grays[static_cast<std::size_t>(head.index)];
    const T level = static_cast<T>(sat_level_);
    const T* in[4] = {nullptr, nullptr, nullptr, nullptr};
    std::uint16_t bits[4] = {0, 0, 0, 0};
    for (int k = 0; k < group.count; ++k) {
        const Step& s = plan_.steps[static_cast<std::size_t>(group.first + k)];
        in[k] = frame_at<T>(s.frame, offset);
        bits[k] = g.weight[static_cast<std::size_t>(s.k)];
        if (s.sat_bits != 0 || s.sat_first)
            saturation_row(in[k], n, level, s.sat_bits, s.sat_first, at(sat_, offset, local));
    }
    const T* threshold =
        g.threshold == GrayThreshold::white_black
            ? threshold_at<T>(white_black_, offset, local)
            : threshold_at<T>(phase_state_[static_cast<std::size_t>(g.phase)].threshold, offset,
                              local);
    std::uint16_t* code = at(code_[static_cast<std::size_t>(head.index)], offset, local);
    switch (group.count) {
    case 1:
        gray_planes_row<T, 1>(in, n, threshold, bits, head.first, code);
        break;
    case 2:
        gray_planes_row<T, 2>(in, n, threshold, bits, head.first, code);
        break;
    case 3:
        gray_planes_row<T, 3>(in, n, threshold, bits, head.first, code);
        break;
    default:
        gray_planes_row<T, 4>(in, n, threshold, bits, head.first, code);
        break;
    }
    if (g.phase < 0)
        for (int k = 0; k < group.count; ++k)
            code_doubt_row(g, in[k], threshold, threshold_at<T>(white_, offset, local),
                           threshold_at<T>(black_, offset, local), n, min_modulation_dn_,
                           doubt_flag(g, plan_.steps[static_cast<std::size_t>(group.first + k)].k),
                           head.first && k == 0,
                           at(code_doubt_[static_cast<std::size_t>(head.index)], offset, local));
}

template <class T>
void DecodeEngine::run_batch_span(std::size_t offset, int n, std::byte* local, float* scratch) {
    // The frames of later steps are read only after the first step's work on
    // this span (a phase block: the heaviest arithmetic); asking for them now
    // lets that arithmetic hide their memory latency.
    const std::size_t bytes = static_cast<std::size_t>(n) * sizeof(T);
    for (int f : prefetch_frames_) {
        const char* p =
            static_cast<const char*>(frame_base_[static_cast<std::size_t>(f)]) + offset * sizeof(T);
        for (std::size_t b = 0; b < bytes; b += kCacheLine)
            __builtin_prefetch(p + b, 0, 2); // read, keep in the outer caches
    }
    for (const BatchGroup& g : batch_groups_) {
        switch (g.kind) {
        case GroupKind::gray_planes:
            run_gray_planes<T>(g, offset, n, local);
            break;
        case GroupKind::single:
            run_step<T>(plan_.steps[static_cast<std::size_t>(g.first)], offset, n, local, scratch);
            break;
        }
    }
    finish_span(offset, n, local, !plan_.needs_full_storage);
}

void DecodeEngine::finish_span(std::size_t offset, int n, std::byte* local, bool with_valid) {
    std::uint8_t* mask = result_.mask.data() + offset;
    const std::uint8_t* sat = at(sat_, offset, local);
    bool first = true;
    for (int a = 0; a < 2; ++a) {
        const AxisPlan& ap = plan_.axes[a];
        if (!ap.coded)
            continue;
        const AxisConstants& k = constants_[a];
        PixelChecks checks;
        checks.min_modulation = min_modulation_dn_;
        checks.max_disagreement = static_cast<float>(options_.max_unwrap_disagreement);
        checks.sat_bit = axis_bit(a);
        checks.valid_flag = single_decider_ ? std::uint8_t{kDecodeValid} : std::uint8_t{0};
        checks.highest = static_cast<float>(ap.extent + 0.5);
        PhaseRow rows[kMaxBlocksPerAxis];
        const int count = static_cast<int>(ap.phases.size());
        for (int i = 0; i < count; ++i) {
            const int b = ap.phases[static_cast<std::size_t>(i)];
            const PhaseState& ps = phase_state_[static_cast<std::size_t>(b)];
            rows[i].fraction = at(ps.fraction, offset, local);
            rows[i].modulation = at(ps.modulation, offset, local);
            rows[i].period =
                static_cast<float>(plan_.phases[static_cast<std::size_t>(b)].block.period);
        }
        float* out = proj_[a] + offset;
        switch (ap.method) {
        case UnwrapMethod::direct:
            unwrap_direct_row(n, rows[0], ap.extent, sat, checks, first, out, mask);
            break;
        case UnwrapMethod::multi_period:
            unwrap_multi_period_row(n, rows, count, ap.extent, sat, checks, first, out, mask);
            break;
        case UnwrapMethod::heterodyne:
            unwrap_heterodyne_row(n, rows, count, k.heterodyne, ap.extent, sat, checks, first, out,
                                  mask);
            break;
        case UnwrapMethod::gray:
            unwrap_gray_row(n, rows[0], at(code_[static_cast<std::size_t>(ap.gray)], offset, local),
                            k.gray, sat, checks, first, out, mask,
                            gray_estimate_[a] != nullptr ? gray_estimate_[a] + offset : nullptr,
                            gray_edge_[a] != nullptr ? gray_edge_[a] + offset : nullptr);
            break;
        case UnwrapMethod::centerline:
            flag_row(n, rows[0], sat, checks, first, mask);
            break;
        case UnwrapMethod::code:
            unwrap_code_row(n, at(code_[static_cast<std::size_t>(ap.gray)], offset, local), k.gray,
                            at(code_modulation_[static_cast<std::size_t>(ap.gray)], offset, local),
                            at(code_doubt_[static_cast<std::size_t>(ap.gray)], offset, local), sat,
                            checks, first, out, mask);
            break;
        case UnwrapMethod::micro: {
            const PhaseState& ps = phase_state_[static_cast<std::size_t>(ap.phases[0])];
            unwrap_micro_row(n, rows[0].fraction, rows[0].modulation,
                             at(ps.ambiguous, offset, local), sat, checks, first, out, mask);
            break;
        }
        }
        first = false;
    }
    if (with_valid && !single_decider_)
        valid_span(offset, n);
}

void DecodeEngine::valid_span(std::size_t offset, int n) {
    const float* coords[2];
    int count = 0;
    for (int a = 0; a < 2; ++a)
        if (proj_[a] != nullptr)
            coords[count++] = proj_[a] + offset;
    valid_row(n, coords, count, result_.mask.data() + offset);
}

void DecodeEngine::global_stages() {
    const int grain = std::max(1, height_ / (8 * pool_.size()));
    for (int a = 0; a < 2; ++a) {
        const AxisPlan& ap = plan_.axes[a];
        if (!ap.coded)
            continue;
        if (gray_estimate_[a] != nullptr) {
            pool_.parallel_for(height_, grain, [&](int y0, int y1, int) {
                repair_plain_gray_rows(plan_.camera, y0, y1, gray_estimate_[a], gray_edge_[a],
                                       constants_[a].repair, proj_[a], result_.mask.data());
            });
        }
        if (ap.method == UnwrapMethod::centerline) {
            const int b = ap.phases[0];
            const PhaseState& ps = phase_state_[static_cast<std::size_t>(b)];
            CenterlineParams params = constants_[a].centerline;
            params.min_modulation = min_modulation_dn_;
            // The finest phase block of the other axis, if any, gates links too.
            const AxisPlan& other_axis = plan_.axes[1 - a];
            const float* other =
                other_axis.coded
                    ? phase_state_[static_cast<std::size_t>(other_axis.report_phase)].fraction.full
                    : nullptr;
            unwrap_centerline(plan_.camera, ps.fraction.full, other, ps.modulation.full, sat_.full,
                              line_[static_cast<std::size_t>(ap.centerline)].full, params, region_,
                              queue_next_, proj_[a], result_.mask.data());
        }
    }
    for_spans(spans_per_task(), [&](std::size_t offset, int n, int) { valid_span(offset, n); });
}

int DecodeEngine::spans_per_task() const {
    // About eight tasks per worker: balance without much claiming.
    return std::max(1, span_count() / (8 * pool_.size()));
}

void DecodeEngine::push(const FrameView& frame) {
    if (mode_ != Mode::streaming)
        throw std::logic_error("push() on a batch decoder");
    if (finished_)
        throw std::logic_error("push() after finish()");
    if (received_ >= plan_.frame_count)
        throw InputError(plan_.origin, "frames",
                         "push(): the sequence has only " + std::to_string(plan_.frame_count) +
                             " frames");
    check_frame(frame, received_);
    if (depth_ == 0) {
        set_depth(frame);
        const std::size_t bytes = area_ * static_cast<std::size_t>(frame.bit_depth / 8);
        if (bytes != slot_bytes_) {
            slots_.clear();
            for (int s = 0; s < plan_.slot_count; ++s)
                slots_.push_back(std::make_unique_for_overwrite<std::byte[]>(bytes));
            slot_bytes_ = bytes;
        }
    }
    const int t = received_;
    const void* data = frame.data;
    frame_base_[static_cast<std::size_t>(t)] = data;
    const int slot = plan_.frame_slot[static_cast<std::size_t>(t)];
    void* slot_data = slot >= 0 ? slots_[static_cast<std::size_t>(slot)].get() : nullptr;
    const std::size_t sample_bytes = static_cast<std::size_t>(frame.bit_depth / 8);
    const std::vector<SpanWork>& work = work_[static_cast<std::size_t>(t)];
    const bool clear_sat = t == clear_sat_at_;
    if (slot_data != nullptr || !work.empty() || clear_sat) {
        for_spans(spans_per_task(), [&](std::size_t offset, int n, int worker) {
            if (slot_data != nullptr)
                std::memcpy(static_cast<std::byte*>(slot_data) + offset * sample_bytes,
                            static_cast<const std::byte*>(data) + offset * sample_bytes,
                            static_cast<std::size_t>(n) * sample_bytes);
            if (clear_sat)
                std::memset(sat_.full + offset, 0, static_cast<std::size_t>(n));
            const int span = static_cast<int>(offset / static_cast<std::size_t>(span_));
            std::byte* local = local_buffer(worker);
            for (const SpanWork& w : work) {
                if (span < w.first_span || span >= w.end_span)
                    continue;
                const Step& step = plan_.steps[static_cast<std::size_t>(w.step)];
                if (depth_ == 8)
                    run_step<std::uint8_t>(step, offset, n, local, scratch_buffer(worker));
                else
                    run_step<std::uint16_t>(step, offset, n, local, scratch_buffer(worker));
            }
        });
    }
    frame_base_[static_cast<std::size_t>(t)] = slot_data;
    ++received_;
}

DecodeResult DecodeEngine::finish() {
    if (finished_)
        throw std::logic_error("finish() called twice");
    if (received_ < plan_.frame_count)
        throw std::logic_error("finish(): " + std::to_string(received_) + " of " +
                               std::to_string(plan_.frame_count) + " frames received");
    const bool neighbourhood = plan_.needs_full_storage;
    for_spans(spans_per_task(), [&](std::size_t offset, int n, int worker) {
        finish_span(offset, n, local_buffer(worker), !neighbourhood);
    });
    if (neighbourhood)
        global_stages();
    finished_ = true;
    return std::move(result_);
}

DecodeResult DecodeEngine::run_batch(std::span<const FrameView> frames) {
    if (mode_ != Mode::batch)
        throw std::logic_error("run_batch() on a streaming decoder");
    if (finished_)
        throw std::logic_error("run_batch() called twice");
    if (static_cast<int>(frames.size()) != plan_.frame_count)
        throw InputError(plan_.origin, "frames",
                         "the capture has " + std::to_string(frames.size()) +
                             " frames but its sequence needs " + std::to_string(plan_.frame_count));
    for (std::size_t f = 0; f < frames.size(); ++f) {
        check_frame(frames[f], static_cast<int>(f));
        if (depth_ == 0)
            set_depth(frames[f]);
        frame_base_[f] = frames[f].data;
    }
    // Each span goes through every frame and the unwrapping while in cache.
    for_spans(spans_per_task(), [&](std::size_t offset, int n, int worker) {
        std::byte* local = local_buffer(worker);
        if (depth_ == 8)
            run_batch_span<std::uint8_t>(offset, n, local, scratch_buffer(worker));
        else
            run_batch_span<std::uint16_t>(offset, n, local, scratch_buffer(worker));
    });
    if (plan_.needs_full_storage)
        global_stages();
    received_ = plan_.frame_count;
    finished_ = true;
    return std::move(result_);
}

} // namespace fpp::detail
