// The reconstruction kernel: phase + coefficient table -> X, Y, Z (and,
// when asked, the predicted sigma of Z from the phase's).
//
// Work is done tile by tile in three plain loops (gather, evaluate, scatter)
// over per-worker scratch buffers. The evaluation loop, where the arithmetic
// is, runs in blocks of kBlock pixels (every tile holds a whole number of
// them) with selects instead of branches, so GCC vectorises it without an
// epilogue for any tile size: NEON on the AArch64 device, SSE on x86-64.
//
// Memory: the kernel streams the whole table once per frame (61 MB for the
// ray model, 107 MB for the polynomial one at 1600x1200), so its speed is
// that of the memory. A tile's planes are 8 or 14 short runs (1 KB for 32x8
// tiles) that hardware prefetchers barely pick up before they end, and the
// same holds for the tile's short phase and cloud rows. So the kernel
// prefetches one tile ahead itself (__builtin_prefetch: plain prefetch
// instructions on every target, never faulting): the next tile's cloud and
// phase rows before the current tile is gathered, and the next tile's
// coefficients in equal parts while the current one is evaluated, which
// keeps the loads spread out instead of queued in a burst. Measured on an
// x86-64 host at 1600x1200 on one thread, this took the kernel from about
// twice the time of a plain copy of its input to below it.

#include "fpp/table_kernel.hpp"

#include "fpp/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace fpp {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kFloatMax = std::numeric_limits<float>::max();
constexpr int kCacheLine = 64; // bytes
// Pixels per evaluation block: one cache line of each plane. Every tile holds
// a whole number of blocks (tile sides are multiples of 8).
constexpr int kBlock = kCacheLine / static_cast<int>(sizeof(float));

// __builtin_prefetch locality hints: 3 keeps the line in every cache level,
// 2 in the outer ones (L2 and beyond).
constexpr int kNearest = 3;
constexpr int kOuter = 2;

// Per-worker counters, on their own cache line.
struct alignas(64) Counts {
    std::size_t phase_valid = 0;
    std::size_t modelled = 0; // finite phase and a model
    std::size_t points = 0;
};

// One tile's scratch: phase in, X, Y, Z out, and the coordinate sigma in
// and sigma_z out in place (tile_pixels floats each).
struct Scratch {
    float* phase;
    float* x;
    float* y;
    float* z;
    float* sigma;
};
constexpr std::size_t kScratchPlanes = 5;

// Tile counters: 32-bit, the width of a float lane, so the counting
// vectorises alongside the arithmetic.
struct TileCounts {
    std::uint32_t phase_valid = 0;
    std::uint32_t modelled = 0;
    std::uint32_t points = 0;
};

// Copies the tile's phase out of the image rows; pixels outside the image get
// NaN (no phase, so no point and not counted).
void gather(const Image<float>& phase, int x0, int y0, int tw, int th, float* out) {
    const int w = std::min(tw, phase.width() - x0);
    for (int r = 0; r < th; ++r) {
        float* dst = out + static_cast<std::size_t>(r) * static_cast<std::size_t>(tw);
        int copied = 0;
        if (y0 + r < phase.height()) {
            std::memcpy(dst, phase.row(y0 + r) + x0, static_cast<std::size_t>(w) * sizeof(float));
            copied = w;
        }
        std::fill(dst + copied, dst + tw, kNaN);
    }
}

// Number of finite values among the tile's `count` phases (a reduction the
// compiler vectorises; no early exit, which would stop it).
std::uint32_t finite_count(const float* __restrict phase, int count) {
    std::uint32_t n = 0;
    for (int i = 0; i < count; ++i)
        n += std::fabs(phase[i]) <= kFloatMax ? 1u : 0u;
    return n;
}

// The prefetch helpers are always inlined: GCC takes a function that only
// prefetches for one without side effects and deletes the calls to it.

// Prefetches `bytes` from `p` on, a cache line at a time, for reading into
// the outer caches.
[[gnu::always_inline]] inline void prefetch(const void* p, std::size_t bytes) {
    const auto* c = static_cast<const char*>(p);
    for (std::size_t o = 0; o < bytes; o += kCacheLine)
        __builtin_prefetch(c + o, 0, kOuter);
}

// Normalised phase of one pixel and what to add to its coordinates: 0 for a
// point, NaN for none; counts the pixel.
//   t = (p - centre) * inv_half_range; NaN or infinite p or centre make t
//   NaN or infinite, so |t| <= 1 alone decides whether there is a point.
// Adding 0 or NaN (rather than selecting the result or NaN) keeps the
// cubics unconditional: GCC would otherwise move them under the condition
// and, since a float operation may trap, no longer vectorise the loop.
struct Normalised {
    float t;
    float nan_if_invalid;
};

inline Normalised normalise(float p, float centre, float inv_half_range, TileCounts& n) {
    const float t = (p - centre) * inv_half_range;
    const bool finite_phase = std::fabs(p) <= kFloatMax;
    const bool model = std::fabs(centre) <= kFloatMax;
    const bool valid = std::fabs(t) <= 1.0f;
    n.phase_valid += finite_phase ? 1u : 0u;
    n.modelled += (finite_phase & model) ? 1u : 0u;
    n.points += valid ? 1u : 0u;
    return {t, valid ? 0.0f : kNaN};
}

// c0 + c1 t + c2 t^2 + c3 t^3 by Horner's rule (c_k at c[k * stride + i]);
// with |t| <= 1 every step is well conditioned (no large powers of t
// cancelling), so float keeps the error to a few ulps of the result.
inline float cubic(const float* c, int stride, int i, float t) {
    return ((c[3 * stride + i] * t + c[2 * stride + i]) * t + c[stride + i]) * t + c[i];
}

// Its derivative in t, c1 + 2 c2 t + 3 c3 t^2, by Horner's rule.
inline float cubic_slope(const float* c, int stride, int i, float t) {
    return (3.0f * c[3 * stride + i] * t + 2.0f * c[2 * stride + i]) * t + c[stride + i];
}

// The evaluators below are not inlined: GCC honours __restrict on a
// function's own parameters, and without it would need more run-time
// overlap checks than it is willing to emit. `ahead` is the next tile (or
// this one when there is none), prefetched `ahead_part` bytes per block.

// X, Y, Z of one tile of model M:
//   polynomial  X, Y and Z cubics in t
//   ray         Z cubic, X = xn Z, Y = yn Z
//   rational    Z = cubic / (1 + d t) (the fit and the loader keep |d| < 1,
//               so the denominator stays positive for |t| <= 1), X = xn Z,
//               Y = yn Z
// With Sigma, `sigma` holds the tile's coordinate sigma (projector px) and
// gets sigma_z = |dZ/dt| * inv_half_range * sigma (mm) in its place:
//   polynomial, ray  dZ/dt = Z cubic's slope
//   rational         dZ/dt = (numerator's slope - Z d) / (1 + d t)
// The model and Sigma are template arguments so that each loop is compiled
// without a per-pixel branch on them.
template <TableModel M, bool Sigma>
[[gnu::noinline]] TileCounts
evaluate(const float* __restrict tile, int tp, const float* __restrict phase, float* __restrict xs,
         float* __restrict ys, float* __restrict zs, float* __restrict sigma, const char* ahead,
         std::size_t ahead_part) {
    namespace tpl = table_plane;
    constexpr bool poly = M == TableModel::polynomial;
    const float* centre = tile + tpl::centre * tp;
    const float* ihr = tile + tpl::inv_half_range * tp;
    static_assert(tpl::ray_z == tpl::rational_z);
    const float* cz = tile + (poly ? tpl::poly_z : tpl::ray_z) * tp;
    const float* cx = tile + tpl::poly_x * tp; // polynomial only
    const float* cy = tile + tpl::poly_y * tp;
    const float* d = tile + tpl::rational_d * tp; // rational only
    const float* xn = tile + (M == TableModel::rational ? tpl::rational_xn : tpl::ray_xn) * tp;
    const float* yn = tile + (M == TableModel::rational ? tpl::rational_yn : tpl::ray_yn) * tp;
    TileCounts n;
    for (int b = 0; b < tp; b += kBlock) {
        prefetch(ahead + static_cast<std::size_t>(b / kBlock) * ahead_part, ahead_part);
        for (int i = b; i < b + kBlock; ++i) {
            const Normalised v = normalise(phase[i], centre[i], ihr[i], n);
            float z = cubic(cz, tp, i, v.t);
            if constexpr (M == TableModel::rational)
                z /= 1.0f + d[i] * v.t;
            if constexpr (Sigma) {
                float dz_dt = cubic_slope(cz, tp, i, v.t);
                if constexpr (M == TableModel::rational)
                    dz_dt = (dz_dt - z * d[i]) / (1.0f + d[i] * v.t);
                sigma[i] = std::fabs(dz_dt * ihr[i]) * sigma[i] + v.nan_if_invalid;
            }
            z += v.nan_if_invalid;
            if constexpr (poly) {
                xs[i] = cubic(cx, tp, i, v.t) + v.nan_if_invalid;
                ys[i] = cubic(cy, tp, i, v.t) + v.nan_if_invalid;
            } else {
                xs[i] = xn[i] * z; // NaN stays NaN
                ys[i] = yn[i] * z;
            }
            zs[i] = z;
        }
    }
    return n;
}

// X, Y, Z of one row into the cloud's interleaved row (GCC vectorises this
// with ST3 on AArch64; x86-64 has no such store and keeps it scalar).
[[gnu::noinline]] void interleave(const float* __restrict x, const float* __restrict y,
                                  const float* __restrict z, int count, float* __restrict xyz) {
    for (int c = 0; c < count; ++c) {
        xyz[3 * c] = x[c];
        xyz[3 * c + 1] = y[c];
        xyz[3 * c + 2] = z[c];
    }
}

// Scatters the tile's X, Y, Z into the cloud rows it covers.
void scatter(const Scratch& s, int x0, int y0, int tw, int th, Image<float>& xyz) {
    const int w = std::min(tw, xyz.width() - x0);
    const int h = std::min(th, xyz.height() - y0);
    for (int r = 0; r < h; ++r) {
        const std::size_t o = static_cast<std::size_t>(r) * static_cast<std::size_t>(tw);
        interleave(s.x + o, s.y + o, s.z + o, w,
                   xyz.row(y0 + r) + static_cast<std::size_t>(x0) * 3);
    }
}

// Copies a tile-sized plane into the rows of a 1-channel image it covers.
void scatter_plane(const float* tile, int x0, int y0, int tw, int th, Image<float>& image) {
    const int w = std::min(tw, image.width() - x0);
    const int h = std::min(th, image.height() - y0);
    for (int r = 0; r < h; ++r)
        std::memcpy(image.row(y0 + r) + x0,
                    tile + static_cast<std::size_t>(r) * static_cast<std::size_t>(tw),
                    static_cast<std::size_t>(w) * sizeof(float));
}

// Writes NaN over the rows of the tile at (x0, y0) of an image, every
// channel (the cloud: no point; sigma_z: none).
void scatter_nothing(int x0, int y0, int tw, int th, Image<float>& image) {
    const int w = std::min(tw, image.width() - x0);
    const int h = std::min(th, image.height() - y0);
    const auto c = static_cast<std::size_t>(image.channels());
    for (int r = 0; r < h; ++r) {
        float* row = image.row(y0 + r) + static_cast<std::size_t>(x0) * c;
        std::fill(row, row + c * static_cast<std::size_t>(w), kNaN);
    }
}

// Prefetches the rows of the tile at (x0, y0), if any, of a 1-channel input
// (for reading, into every cache level: the gather comes next) and of an
// output of `out_channels` channels (for writing).
[[gnu::always_inline]] inline void prefetch_rows(const Image<float>& in_image,
                                                 Image<float>& out_image, int out_channels, int x0,
                                                 int y0, int tw, int th) {
    if (y0 >= in_image.height())
        return;
    const int w = std::min(tw, in_image.width() - x0);
    const int h = std::min(th, in_image.height() - y0);
    const auto in_bytes = static_cast<std::size_t>(w) * sizeof(float);
    const auto c = static_cast<std::size_t>(out_channels);
    for (int r = 0; r < h; ++r) {
        const auto* in =
            static_cast<const char*>(static_cast<const void*>(in_image.row(y0 + r) + x0));
        for (std::size_t o = 0; o < in_bytes; o += kCacheLine)
            __builtin_prefetch(in + o, 0, kNearest);
        auto* out = static_cast<char*>(
            static_cast<void*>(out_image.row(y0 + r) + static_cast<std::size_t>(x0) * c));
        for (std::size_t o = 0; o < c * in_bytes; o += kCacheLine)
            __builtin_prefetch(out + o, 1, kOuter);
    }
}

using Evaluator = TileCounts (*)(const float*, int, const float*, float*, float*, float*, float*,
                                 const char*, std::size_t);

template <bool Sigma> Evaluator evaluator(TableModel model) {
    return model == TableModel::ray        ? evaluate<TableModel::ray, Sigma>
           : model == TableModel::rational ? evaluate<TableModel::rational, Sigma>
                                           : evaluate<TableModel::polynomial, Sigma>;
}

std::string size_text(const Image<float>& image) {
    return std::to_string(image.width()) + "x" + std::to_string(image.height()) + "x" +
           std::to_string(image.channels());
}

} // namespace

TableApplyStats apply_table(const CoefficientTable& table, const Image<float>& phase,
                            PointCloud& cloud, ThreadPool* pool,
                            const Image<float>* coordinate_sigma) {
    if (table.empty())
        throw std::invalid_argument("apply_table: empty coefficient table");
    const TableInfo& info = table.info();
    for (const Image<float>* in : {&phase, coordinate_sigma})
        if (in != nullptr && (in->size() != info.camera || in->channels() != 1))
            throw std::invalid_argument(std::string("apply_table: the ") +
                                        (in == &phase ? "phase" : "sigma") + " image is " +
                                        size_text(*in) + ", the table wants " +
                                        std::to_string(info.camera.width) + "x" +
                                        std::to_string(info.camera.height) + "x1");
    if (cloud.xyz.size() != info.camera || cloud.xyz.channels() != 3)
        cloud.xyz = Image<float>(info.camera, 3);
    const bool with_sigma = coordinate_sigma != nullptr;
    if (!with_sigma)
        cloud.sigma_z = Image<float>();
    else if (cloud.sigma_z.size() != info.camera || cloud.sigma_z.channels() != 1)
        cloud.sigma_z = Image<float>(info.camera, 1);

    ThreadPool& workers = pool ? *pool : ThreadPool::shared();
    const int tw = info.tile_width;
    const int th = info.tile_height;
    const int tp = info.tile_pixels();
    const int tiles_x = info.tiles_x();
    const int tiles_y = info.tiles_y();
    const Evaluator evaluate_tile =
        with_sigma ? evaluator<true>(info.model) : evaluator<false>(info.model);
    const auto tile_floats = static_cast<std::size_t>(tp);
    const std::size_t tile_bytes =
        static_cast<std::size_t>(table.planes()) * tile_floats * sizeof(float);
    const std::size_t ahead_part = tile_bytes / (tile_floats / kBlock); // = planes cache lines
    const auto worker_count = static_cast<std::size_t>(workers.size());

    // One scratch and one set of counters per worker, for the whole call.
    std::vector<float> scratch(worker_count * kScratchPlanes * tile_floats);
    std::vector<Counts> counts(worker_count);

    // Rows of tiles, a few chunks per worker so uneven cores balance out.
    const int grain = std::max(1, tiles_y / (4 * workers.size()));
    workers.parallel_for(tiles_y, grain, [&](int ty_begin, int ty_end, int worker) {
        float* base =
            scratch.data() + static_cast<std::size_t>(worker) * kScratchPlanes * tile_floats;
        const Scratch s{base, base + tile_floats, base + 2 * tile_floats, base + 3 * tile_floats,
                        base + 4 * tile_floats};
        Counts& c = counts[static_cast<std::size_t>(worker)];
        for (int ty = ty_begin; ty < ty_end; ++ty) {
            for (int tx = 0; tx < tiles_x; ++tx) {
                const int x0 = tx * tw;
                const int y0 = ty * th;
                // The next tile in memory and in this loop's order.
                const bool last_in_row = tx + 1 == tiles_x;
                const bool last = last_in_row && ty + 1 == tiles_y;
                const int next_x = last_in_row ? 0 : x0 + tw;
                const int next_y = last_in_row ? y0 + th : y0;
                prefetch_rows(phase, cloud.xyz, 3, next_x, next_y, tw, th);
                if (with_sigma)
                    prefetch_rows(*coordinate_sigma, cloud.sigma_z, 1, next_x, next_y, tw, th);
                gather(phase, x0, y0, tw, th, s.phase);
                // Background (no phase decoded anywhere in the tile): its
                // coefficients, most of the bytes read, are not needed.
                if (finite_count(s.phase, tp) == 0) {
                    scatter_nothing(x0, y0, tw, th, cloud.xyz);
                    if (with_sigma)
                        scatter_nothing(x0, y0, tw, th, cloud.sigma_z);
                    continue;
                }
                if (with_sigma)
                    gather(*coordinate_sigma, x0, y0, tw, th, s.sigma);
                const float* tile = table.tile(tx, ty);
                const char* ahead = static_cast<const char*>(static_cast<const void*>(tile)) +
                                    (last ? 0 : tile_bytes);
                const TileCounts n =
                    evaluate_tile(tile, tp, s.phase, s.x, s.y, s.z, s.sigma, ahead, ahead_part);
                scatter(s, x0, y0, tw, th, cloud.xyz);
                if (with_sigma)
                    scatter_plane(s.sigma, x0, y0, tw, th, cloud.sigma_z);
                c.phase_valid += n.phase_valid;
                c.modelled += n.modelled;
                c.points += n.points;
            }
        }
    });

    TableApplyStats stats;
    std::size_t modelled = 0;
    for (const Counts& c : counts) {
        stats.phase_valid += c.phase_valid;
        modelled += c.modelled;
        stats.points += c.points;
    }
    stats.no_model = stats.phase_valid - modelled;
    stats.out_of_range = modelled - stats.points;
    return stats;
}

} // namespace fpp
