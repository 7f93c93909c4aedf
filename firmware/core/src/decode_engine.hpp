#pragma once
// The decoder's state and its execution of a plan (decode_plan.hpp), shared by
// the streaming form (frames pushed one by one, per-frame work in push, state
// in full-size planes) and the batch form (all frames at hand: each row goes
// through every step and the unwrapping while it is in cache, with state in
// one row per worker unless a neighbourhood stage needs whole images). Both
// apply the same operations in the same order to every pixel, without
// floating-point contraction (phase_math.hpp), so they are bit-identical.

#include "decode_plan.hpp"
#include "fpp/decoder.hpp"
#include "fpp/parallel.hpp"
#include "unwrap_spatial.hpp"
#include "unwrap_temporal.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace fpp::detail {

// A per-pixel array: either full-size (`full`) or one row in each worker's
// row buffer at byte offset `local` (batch mode without neighbourhood stages).
template <class T> struct PlaneRef {
    T* full = nullptr;
    std::size_t local = 0;
};

// Per-axis constants derived from the plan.
struct AxisConstants {
    GrayRowParams gray;
    GrayRepairParams repair;
    CenterlineParams centerline;
    std::vector<HeterodyneStep> heterodyne;
};

class DecodeEngine {
public:
    enum class Mode { streaming, batch };
    // `recycled`: a previous result whose images are reused when their size
    // fits (may be null).
    DecodeEngine(Plan plan, const DecodeOptions& options, Mode mode,
                 DecodeResult* recycled = nullptr);

    int frames_received() const { return received_; }
    int frames_expected() const { return plan_.frame_count; }

    void push(const Frame& frame);
    DecodeResult finish();
    DecodeResult run_batch(const std::vector<Frame>& frames);

private:
    struct PhaseState {
        PlaneRef<float> fraction; // cos sum, then wrapped fraction
        PlaneRef<float> modulation; // sin sum, then B
        PlaneRef<float> mean;     // sum, then A
        PlaneRef<std::uint16_t> threshold; // floor(A) when gray/centerline use it
    };

    template <class T> PlaneRef<T> make_plane(std::vector<std::unique_ptr<T[]>>& store, bool full);
    template <class T> T* row(const PlaneRef<T>& p, int y, std::byte* local) const {
        return p.full != nullptr ? p.full + static_cast<std::size_t>(y) * static_cast<std::size_t>(width_)
                                 : reinterpret_cast<T*>(local + p.local);
    }
    std::byte* local_buffer(int worker) const;

    void allocate_result(DecodeResult* recycled);
    void check_frame(const Frame& frame, int index) const;
    void set_depth(int bit_depth);
    template <class T> void run_step(const Step& step, int y, std::byte* local) const;
    void run_step_any(const Step& step, int y, std::byte* local) const;
    // Batch mode: up to four consecutive steps of one kind and block at once.
    struct StepGroup {
        int first = 0; // index in plan_.steps
        int count = 1;
    };
    template <class T> void run_group(const StepGroup& group, int y, std::byte* local) const;
    void run_group_any(const StepGroup& group, int y, std::byte* local) const;
    void finish_row(int y, std::byte* local, bool with_valid);
    void valid_row_at(int y);
    void global_stages();

    Plan plan_;
    DecodeOptions options_;
    Mode mode_;
    ThreadPool pool_;
    AxisConstants constants_[2];
    int width_ = 0;
    int height_ = 0;
    bool full_ = true;
    bool single_decider_ = false; // one coded axis, no neighbourhood stage: kernels set kDecodeValid

    // Depth-dependent constants, set by the first frame.
    int depth_ = 0;
    std::uint16_t sat_level_ = 0;
    float min_modulation_dn_ = 0;

    std::vector<PhaseState> phase_state_; // per plan phase block (unused: empty refs)
    std::vector<PlaneRef<std::uint16_t>> code_; // per gray block
    std::vector<PlaneRef<std::uint8_t>> line_;  // per centerline block
    PlaneRef<std::uint16_t> white_black_; // floor((white + black) / 2)
    PlaneRef<std::uint8_t> sat_;

    std::vector<std::unique_ptr<float[]>> float_store_;
    std::vector<std::unique_ptr<std::uint16_t[]>> u16_store_;
    std::vector<std::unique_ptr<std::uint8_t[]>> u8_store_;
    std::vector<std::unique_ptr<std::int32_t[]>> i32_store_;
    std::size_t local_bytes_ = 0;
    std::vector<std::unique_ptr<std::byte[]>> local_rows_; // per worker

    // Neighbourhood stages (full storage): plain Gray estimate and edge marks,
    // centerline region labels and queue links.
    float* gray_estimate_[2] = {nullptr, nullptr};
    std::uint8_t* gray_edge_[2] = {nullptr, nullptr};
    std::int32_t* region_ = nullptr;
    std::int32_t* queue_next_ = nullptr;

    DecodeResult result_;
    float* proj_[2] = {nullptr, nullptr};

    // Frames: row source per frame index, waiting slots.
    std::vector<const void*> frame_base_;
    std::vector<std::unique_ptr<std::uint16_t[]>> slots_; // sized for 16-bit
    std::vector<StepGroup> batch_groups_; // plan_.steps grouped for run_batch
    std::vector<int> step_begin_; // per trigger frame: range in plan_.steps
    std::vector<int> step_end_;
    int received_ = 0;
    bool finished_ = false;
};

} // namespace fpp::detail
