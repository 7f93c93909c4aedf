#include "unwrap_spatial.hpp"

#include "fpp/decoder.hpp"
#include "phase_math.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace fpp::detail {

namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
} // namespace

void repair_plain_gray_rows(Size size, int y0, int y1, const float* estimate,
                            const std::uint8_t* edge, const GrayRepairParams& params, float* out,
                            std::uint8_t* mask) {
    const int w = size.width;
    const int h = size.height;
    const float period = params.period;
    const float tol = params.tolerance;
    const float max_step = params.max_slope;
    const int reach = params.reach;
    const int dx[4] = {-1, 1, 0, 0};
    const int dy[4] = {0, 0, -1, 1};
    for (int y = y0; y < y1; ++y) {
        for (int x = 0; x < w; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
                                  static_cast<std::size_t>(x);
            const float p = estimate[i];
            if (edge[i] == 0 || !(p == p)) continue;
            int votes[3] = {0, 0, 0}; // p - period, p, p + period
            for (int d = 0; d < 4; ++d) {
                // The first two non-edge pixels in this direction extrapolate
                // the surface to this pixel.
                float found[2] = {0, 0};
                int dist[2] = {0, 0};
                int n = 0;
                for (int step = 1; step <= reach && n < 2; ++step) {
                    const int u = x + dx[d] * step, v = y + dy[d] * step;
                    if (u < 0 || u >= w || v < 0 || v >= h) break;
                    const std::size_t j = static_cast<std::size_t>(v) * static_cast<std::size_t>(w) +
                                          static_cast<std::size_t>(u);
                    const float q = estimate[j];
                    if (!(q == q)) break; // no surface: the walk ends
                    if (edge[j] != 0) continue;
                    found[n] = q;
                    dist[n] = step;
                    ++n;
                }
                if (n < 2) continue;
                const float gap = static_cast<float>(dist[1] - dist[0]);
                const float slope = (found[0] - found[1]) / gap;
                if (abs_fast(slope) > max_step) continue; // the two straddle a step
                const float predicted = found[0] + slope * static_cast<float>(dist[0]);
                for (int c = 0; c < 3; ++c)
                    if (abs_fast(predicted - (p + static_cast<float>(c - 1) * period)) <= tol)
                        ++votes[c];
            }
            // Move only when every direction that speaks agrees.
            const int speaking = (votes[0] > 0) + (votes[1] > 0) + (votes[2] > 0);
            if (speaking == 1) {
                const int c = votes[0] > 0 ? 0 : votes[1] > 0 ? 1 : 2;
                out[i] = p + static_cast<float>(c - 1) * period;
            } else {
                out[i] = kNaN;
                mask[i] = static_cast<std::uint8_t>(mask[i] | kDecodeUnwrapInconsistent);
            }
        }
    }
}

void unwrap_centerline(Size size, const float* fraction, const float* modulation,
                       const std::uint8_t* sat, const std::uint8_t* line,
                       const CenterlineParams& params, std::int32_t* region, std::int32_t* next,
                       float* out, std::uint8_t* mask) {
    const int w = size.width;
    const int h = size.height;
    const std::int32_t count = static_cast<std::int32_t>(size.area());
    const float period = params.period;
    const float inv = 1.0f / period;
    constexpr int kBuckets = 64;
    const float bucket_scale = static_cast<float>(kBuckets - 1) / params.jump_gate;

    for (std::int32_t i = 0; i < count; ++i) {
        const bool ok = modulation[i] >= params.min_modulation && (sat[i] & params.sat_bit) == 0;
        region[i] = ok ? -1 : -2;
    }

    // Regions, each grown from its first pixel in raster order along the
    // smoothest links first. `out` holds the relative unwrapped coordinate.
    std::int32_t regions = 0;
    std::int32_t head[kBuckets];
    for (std::int32_t seed = 0; seed < count; ++seed) {
        if (region[seed] != -1) continue;
        const std::int32_t id = regions++;
        std::fill(head, head + kBuckets, -1);
        region[seed] = id;
        out[seed] = fraction[seed] * period;
        next[seed] = -1;
        head[0] = seed;
        int lowest = 0;
        for (;;) {
            while (lowest < kBuckets && head[lowest] < 0) ++lowest;
            if (lowest == kBuckets) break;
            const std::int32_t a = head[lowest];
            head[lowest] = next[a];
            const int ax = a % w, ay = a / w;
            const float ua = out[a];
            const float fa = fraction[a];
            const std::int32_t neighbours[4] = {ax > 0 ? a - 1 : -1, ax + 1 < w ? a + 1 : -1,
                                                ay > 0 ? a - w : -1, ay + 1 < h ? a + w : -1};
            for (std::int32_t b : neighbours) {
                if (b < 0 || region[b] != -1) continue;
                float d = fraction[b] - fa;
                d -= round_fast(d);
                const float ad = abs_fast(d);
                if (ad > params.jump_gate) continue;
                region[b] = id;
                const float pw = fraction[b] * period;
                out[b] = pw + round_fast((ua - pw) * inv) * period;
                const int bucket = std::min(kBuckets - 1, static_cast<int>(ad * bucket_scale));
                next[b] = head[bucket];
                head[bucket] = b;
                lowest = std::min(lowest, bucket);
            }
        }
    }

    // Votes of the centerline pixels: (region, fringe-order offset).
    std::vector<std::pair<std::int32_t, std::int32_t>> votes;
    const double position = params.position;
    const double period_d = static_cast<double>(period);
    const double reach = params.half_width + 1.0;
    for (std::int32_t i = 0; i < count; ++i) {
        if (line[i] == 0 || region[i] < 0) continue;
        double offset = static_cast<double>(fraction[i]) * period_d - position;
        offset -= period_d * std::floor(offset / period_d + 0.5);
        if (std::abs(offset) > reach) continue;
        const auto k = static_cast<std::int32_t>(std::lround((position - static_cast<double>(out[i])) / period_d));
        votes.emplace_back(region[i], k);
    }
    std::sort(votes.begin(), votes.end());
    std::vector<float> shift(static_cast<std::size_t>(regions), kNaN);
    std::vector<std::uint8_t> flag(static_cast<std::size_t>(regions), kDecodeNoCue);
    for (std::size_t s = 0; s < votes.size();) {
        const std::int32_t id = votes[s].first;
        std::size_t e = s;
        int total = 0, best = 0;
        std::int32_t best_k = 0;
        while (e < votes.size() && votes[e].first == id) {
            std::size_t f = e;
            while (f < votes.size() && votes[f] == votes[e]) ++f;
            const int n = static_cast<int>(f - e);
            total += n;
            if (n > best) {
                best = n;
                best_k = votes[e].second;
            }
            e = f;
        }
        if (best >= params.min_votes && 3 * best >= 2 * total) {
            shift[static_cast<std::size_t>(id)] = static_cast<float>(best_k) * period;
            flag[static_cast<std::size_t>(id)] = 0;
        } else {
            flag[static_cast<std::size_t>(id)] = total >= params.min_votes ? kDecodeUnwrapInconsistent
                                                                           : kDecodeNoCue;
        }
        s = e;
    }

    for (std::int32_t i = 0; i < count; ++i) {
        const std::int32_t id = region[i];
        if (id < 0) {
            out[i] = kNaN; // flagged already (low modulation or saturated)
            continue;
        }
        const float s = shift[static_cast<std::size_t>(id)];
        out[i] = s == s ? out[i] + s : kNaN;
        mask[i] = static_cast<std::uint8_t>(mask[i] | flag[static_cast<std::size_t>(id)]);
    }
}

} // namespace fpp::detail
