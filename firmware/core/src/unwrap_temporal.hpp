#pragma once
// Per-row temporal unwrapping: wrapped fractions (decode_kernels.hpp) plus a
// cue (Gray code, coarser periods, beats) -> projector coordinate per pixel.
// Each kernel writes the coordinate (NaN where invalid) and ORs its DecodeFlag
// bits into the mask (or assigns them when `mask_first`).

#include <cstdint>
#include <vector>

namespace fpp::detail {

// What every kernel needs about validity.
struct PixelChecks {
    float min_modulation = 0;       // DN
    float max_disagreement = 0.35f; // fine periods
    std::uint8_t sat_bit = 1;       // this axis's saturation bit
    // kDecodeValid when this kernel alone decides validity (one coded axis,
    // no neighbourhood stage): set where no flag is raised. Else 0.
    std::uint8_t valid_flag = 0;
    // Projector range along the axis, with a pixel of margin: a coordinate
    // outside it cannot have been lit, so the unwrapping went wrong.
    float lowest = -1.5f;
    float highest = 1e30f;
};

// A phase block's per-row data after phase_finish_row.
struct PhaseRow {
    const float* fraction = nullptr; // wrapped fraction of a period in [0, 1)
    const float* modulation = nullptr;
    float period = 0;
};

// One block covering the extent: p = fraction * period, moved into the window
// [lo, lo + period) with lo = -0.5 - (period - extent) / 2 (centred on the projector).
void unwrap_direct_row(int n, const PhaseRow& phase, double extent, const std::uint8_t* sat,
                       const PixelChecks& checks, bool mask_first, float* out, std::uint8_t* mask);

// Hierarchical: blocks[0] covers the extent, each next block is unwrapped with
// the previous estimate (coarse to fine).
void unwrap_multi_period_row(int n, const PhaseRow* blocks, int count, double extent,
                             const std::uint8_t* sat, const PixelChecks& checks, bool mask_first,
                             float* out, std::uint8_t* mask);

// Heterodyne chain (levels root to fine, see decode_plan.hpp). `blocks` in the
// plan's ascending period order. The result is the weighted mean of the
// unwrapped single blocks (weights 1/period^2: equal phase noise).
struct HeterodyneStep {
    float period = 0;
    float coef[3] = {0, 0, 0};
    int single = -1;
};
void unwrap_heterodyne_row(int n, const PhaseRow* blocks, int count,
                           const std::vector<HeterodyneStep>& levels, double extent,
                           const std::uint8_t* sat, const PixelChecks& checks, bool mask_first,
                           float* out, std::uint8_t* mask);

// Gray-code unwrapping. The code of projector pixel i is floor(i / unit) with
// unit = period (plain) or period / 2 (complementary); with bilinear projection
// its interval is [ceil(K unit) - 0.5, ceil((K + 1) unit) - 0.5]. The fringe
// order is the candidate p_w + m period nearest to the interval centre.
// Complementary: flags pixels farther than max_disagreement periods from the
// centre. Plain: marks pixels within `edge_band` px of the interval edges in
// `edge` (for the neighbour repair) and stores the estimate in `estimate`.
// fpp-capture/2 codes (binary, n-ary, shifted) go through `step_of_code`
// (code value -> step K, GrayInfo::step_of_code) and the interval becomes
// [ceil(offset + K unit) - 0.5, ceil(offset + (K + 1) unit) - 0.5]; steps
// above max_step (unused code values) are flagged inconsistent.
struct GrayRowParams {
    float period = 0;
    float unit = 0;
    std::uint32_t max_code = 0; // largest K seen inside the projector
    bool complementary = true;
    float edge_band = 0;
    const float* step_of_code = nullptr; // null: plain Gray, K = gray_to_binary(code)
    float offset = 0;
    float max_step = 0;
    bool resolve_carries = false;           // code-only natural binary: see unwrap_code_row
    const float* code_coordinate = nullptr; // code-only: GrayInfo::code_coordinate
    std::uint32_t code_count = 0;           // code values (half the table)
    std::uint32_t max_carry_run = 0;        // resolve_carries: longest run (2^(j+1) - 1)
    // GrayBlock::wrap: L^D steps (px). A coordinate below -1/2 from the code
    // of the first step is the wrapped last step: it moves up by this much.
    float wrap_span = 0;
};
void unwrap_gray_row(int n, const PhaseRow& phase, const std::uint16_t* code,
                     const GrayRowParams& params, const std::uint8_t* sat,
                     const PixelChecks& checks, bool mask_first, float* out, std::uint8_t* mask,
                     float* estimate, std::uint8_t* edge);

// Code-only axis: the coordinate of code value v is code_coordinate[v], the
// centre of the projector pixels that show its step K, (ceil(offset + K unit)
// + ceil(offset + (K + 1) unit)) / 2 - 1/2; unused code values (NaN there) are
// flagged inconsistent; low `modulation` (DN) is low modulation. `doubt` holds
// a flag per doubtful plane. Gray and n-ary codes: two or more doubtful
// planes are low modulation (one is a code edge). With resolve_carries
// (natural binary, `doubt` holds the planes' code weights): with j the most
// significant doubtful digit, digits 0..j are taken as unknown (the sure ones
// below j too: a carry edge changes them all, and a finest digit blurred to
// grey reads as sure at chance) and the pixel as lying on the one edge inside
// their cell where they all change (..0111 | ..1000, the cell's centre),
// code_coordinate[count + upper value]; a run longer than max_carry_run
// (2^(j+1) - 1) is low modulation. That is
// the best estimate both where the pixel straddles a carry edge and where
// the finest digits are unreadable (a least significant plane blurred to
// grey): see test_decode_families.cpp.
void unwrap_code_row(int n, const std::uint16_t* code, const GrayRowParams& params,
                     const float* modulation, const std::uint16_t* doubt, const std::uint8_t* sat,
                     const PixelChecks& checks, bool mask_first, float* out, std::uint8_t* mask);

// Micro phase: the coordinate found by micro_search (decode_micro.hpp);
// `ambiguous` pixels are flagged inconsistent.
void unwrap_micro_row(int n, const float* coordinate, const float* modulation,
                      const std::uint8_t* ambiguous, const std::uint8_t* sat,
                      const PixelChecks& checks, bool mask_first, float* out, std::uint8_t* mask);

// Validity flags only (the coordinate comes later from spatial unwrapping).
void flag_row(int n, const PhaseRow& phase, const std::uint8_t* sat, const PixelChecks& checks,
              bool mask_first, std::uint8_t* mask);

// mask |= kDecodeValid where every given coordinate row is finite.
void valid_row(int n, const float* const* coords, int count, std::uint8_t* mask);

} // namespace fpp::detail
