#pragma once
// The decoder's state and its execution of a plan (decode_plan.hpp), shared by
// the streaming form (frames pushed one by one; each step runs once the frames
// it reads are there, a phase block in slices of its spans from its last frame
// on (Step::parts) with its frames kept in slots; state in full-size planes)
// and the batch form (all frames at hand). Work is done on spans: runs of
// consecutive pixels in row-major order (a span may cross rows; no per-pixel
// kernel looks at a neighbour). The batch
// form takes one span at a time through every step and the unwrapping while
// the span is in cache, with its state in one span-sized buffer per worker
// unless a neighbourhood stage needs whole images; so each input sample is
// read once and each output written once. Both forms run the same kernels on
// the same samples, without floating-point contraction (phase_math.hpp), so
// they are bit-identical.

#include "decode_plan.hpp"
#include "fpp/decoder.hpp"
#include "fpp/parallel.hpp"
#include "unwrap_spatial.hpp"
#include "unwrap_temporal.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace fpp::detail {

// A per-pixel array: either full-size (`full`) or one span in each worker's
// span buffer at byte offset `local` (batch mode without neighbourhood stages).
template <class T> struct PlaneRef {
    T* full = nullptr;
    std::size_t local = 0;
};

// Per-axis constants derived from the plan.
struct AxisConstants {
    GrayRowParams gray;
    GrayRepairParams repair;
    CenterlineParams centerline;
    float code_unit = 0;   // code-only: projector px per code step
    float code_offset = 0; // code-only: projector px
    std::vector<HeterodyneStep> heterodyne;
};

// Axis `a`'s constants (decode_axis_constants.cpp).
AxisConstants axis_constants(const Plan& plan, int a);

class DecodeEngine {
public:
    enum class Mode { streaming, batch };
    // `recycled`: a previous result whose images are reused when their size
    // fits (may be null).
    DecodeEngine(Plan plan, const DecodeOptions& options, Mode mode,
                 DecodeResult* recycled = nullptr);

    int frames_received() const { return received_; }
    int frames_expected() const { return plan_.frame_count; }

    void push(const FrameView& frame);
    DecodeResult finish();
    // Streaming: back to the first frame, keeping the state planes and slots.
    void restart(DecodeResult* recycled);
    DecodeResult run_batch(std::span<const FrameView> frames);

private:
    struct PhaseState {
        PlaneRef<float> fraction;   // cos sum, then wrapped fraction
        PlaneRef<float> modulation; // sin sum, then B
        PlaneRef<float> mean;       // sum, then A
        // floor(A) in the frames' sample type when gray/centerline use it
        // (16-bit storage, read as 8-bit for 8-bit frames).
        PlaneRef<std::uint16_t> threshold;
        PlaneRef<std::uint8_t> ambiguous; // micro: 1 where the column is not clearly best
    };

    // Batch mode: the plan's steps in order, runs of gray planes of one block
    // thresholded against one image grouped (up to four planes per pass).
    enum class GroupKind { gray_planes, single };
    struct BatchGroup {
        GroupKind kind = GroupKind::single;
        int first = 0; // index in plan_.steps
        int count = 1;
    };

    template <class T> PlaneRef<T> make_plane(std::vector<std::unique_ptr<T[]>>& store, bool full);
    // Start of a plane's data for the span beginning at pixel `offset`.
    template <class T> T* at(const PlaneRef<T>& p, std::size_t offset, std::byte* local) const {
        return p.full != nullptr ? p.full + offset : reinterpret_cast<T*>(local + p.local);
    }
    // A threshold plane viewed in the sample type T.
    template <class T>
    T* threshold_at(const PlaneRef<std::uint16_t>& p, std::size_t offset, std::byte* local) const {
        return p.full != nullptr ? reinterpret_cast<T*>(p.full) + offset
                                 : reinterpret_cast<T*>(local + p.local);
    }
    template <class T> const T* frame_at(int frame, std::size_t offset) const {
        return static_cast<const T*>(frame_base_[static_cast<std::size_t>(frame)]) + offset;
    }
    std::byte* local_buffer(int worker) const;

    void allocate_result(DecodeResult* recycled);
    void bind_report_planes();
    void build_batch_groups();
    void build_streaming_work();
    void check_frame(const FrameView& frame, int index) const;
    void set_depth(const FrameView& first);
    template <class T>
    void run_step(const Step& step, std::size_t offset, int n, std::byte* local,
                  float* scratch) const;
    template <class T>
    void run_phase_block(const Step& step, std::size_t offset, int n, std::byte* local,
                         float* scratch) const;
    // decode_engine_families.cpp: 2+1, modulated and micro blocks, n-ary
    // digits, white/black levels and code-only modulation.
    template <class T>
    void run_family_block(const Step& step, std::size_t offset, int n, std::byte* local,
                          float* scratch) const;
    template <class T>
    void run_family_step(const Step& step, std::size_t offset, int n, std::byte* local) const;
    float* scratch_buffer(int worker) const;
    template <class T>
    void run_gray_planes(const BatchGroup& group, std::size_t offset, int n,
                         std::byte* local) const;
    template <class T>
    void run_batch_span(std::size_t offset, int n, std::byte* local, float* scratch);
    void finish_span(std::size_t offset, int n, std::byte* local, bool with_valid);
    void valid_span(std::size_t offset, int n);
    void global_stages();
    // Calls fn(offset, n, worker) on every span of the image, in parallel.
    template <class F> void for_spans(int spans_per_task, F&& fn);
    int span_count() const;
    int spans_per_task() const;

    Plan plan_;
    DecodeOptions options_;
    Mode mode_;
    ThreadPool& pool_; // shared (ThreadPool::shared)
    AxisConstants constants_[2];
    int width_ = 0;
    int height_ = 0;
    std::size_t area_ = 0;
    int span_ = 0; // pixels per span
    bool full_ = true;
    bool single_decider_ =
        false; // one coded axis, no neighbourhood stage: kernels set kDecodeValid

    // Depth-dependent constants, set by the first frame.
    int depth_ = 0;
    std::uint16_t sat_level_ = 0;
    float min_modulation_dn_ = 0;
    float full_scale_ = 0; // of the bits in use (Frame::max_value)

    std::vector<PhaseState> phase_state_;       // per plan phase block (unused: empty refs)
    std::vector<PlaneRef<std::uint16_t>> code_; // per gray block
    std::vector<PlaneRef<std::uint8_t>> line_;  // per centerline block
    PlaneRef<std::uint16_t> white_black_;       // floor((white + black) / 2), sample type
    PlaneRef<std::uint16_t> white_, black_;     // white and black frames (Plan::uses_levels)
    // Code-only axes: modulation and mean per gray block (the result's images
    // for the reported axis).
    std::vector<PlaneRef<float>> code_modulation_, code_mean_;
    std::vector<PlaneRef<std::uint16_t>> code_doubt_; // doubtful planes (doubt_threshold_row)
    // Per worker scratch of the modulated and micro kernels (scratch_floats_
    // floats per pixel of a span).
    int scratch_floats_ = 0;
    std::vector<std::unique_ptr<float[]>> scratch_;
    PlaneRef<std::uint8_t> sat_;

    std::vector<std::unique_ptr<float[]>> float_store_;
    std::vector<std::unique_ptr<std::uint16_t[]>> u16_store_;
    std::vector<std::unique_ptr<std::uint8_t[]>> u8_store_;
    std::vector<std::unique_ptr<std::int32_t[]>> i32_store_;
    std::size_t local_bytes_ = 0;
    std::vector<std::unique_ptr<std::byte[]>> local_spans_; // per worker

    // Neighbourhood stages (full storage): plain Gray estimate and edge marks,
    // centerline region labels and queue links.
    float* gray_estimate_[2] = {nullptr, nullptr};
    std::uint8_t* gray_edge_[2] = {nullptr, nullptr};
    std::int32_t* region_ = nullptr;
    std::int32_t* queue_next_ = nullptr;

    DecodeResult result_;
    float* proj_[2] = {nullptr, nullptr};

    // Frames: sample source per frame index, waiting slots.
    std::vector<const void*> frame_base_;
    // Streaming: frames read after their arrival (a phase block's frames wait
    // for its last), allocated at the first frame for its sample size.
    std::vector<std::unique_ptr<std::byte[]>> slots_;
    std::size_t slot_bytes_ = 0; // bytes of each slot
    std::vector<BatchGroup> batch_groups_;
    std::vector<int> prefetch_frames_; // batch: frames asked for at the start of a span
    // Streaming: what each pushed frame runs, in plan order: a step on the
    // spans [first_span, end_span) (all spans, but for a phase block's slice).
    struct SpanWork {
        int step = 0; // index in plan_.steps
        int first_span = 0;
        int end_span = 0;
    };
    std::vector<std::vector<SpanWork>> work_; // per frame index
    // Frame at which the saturation bytes are cleared: the first step that
    // writes them is a sliced phase block, whose slices OR into them.
    int clear_sat_at_ = -1;
    int received_ = 0;
    bool finished_ = false;
};

} // namespace fpp::detail
