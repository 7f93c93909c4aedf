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
            if (edge[i] == 0 || !(p == p))
                continue;
            int votes[3] = {0, 0, 0}; // p - period, p, p + period
            for (int d = 0; d < 4; ++d) {
                // The first two non-edge pixels in this direction extrapolate
                // the surface to this pixel.
                float found[2] = {0, 0};
                int dist[2] = {0, 0};
                int n = 0;
                for (int step = 1; step <= reach && n < 2; ++step) {
                    const int u = x + dx[d] * step, v = y + dy[d] * step;
                    if (u < 0 || u >= w || v < 0 || v >= h)
                        break;
                    const std::size_t j =
                        static_cast<std::size_t>(v) * static_cast<std::size_t>(w) +
                        static_cast<std::size_t>(u);
                    const float q = estimate[j];
                    if (!(q == q))
                        break; // no surface: the walk ends
                    if (edge[j] != 0)
                        continue;
                    found[n] = q;
                    dist[n] = step;
                    ++n;
                }
                if (n < 2)
                    continue;
                const float gap = static_cast<float>(dist[1] - dist[0]);
                const float slope = (found[0] - found[1]) / gap;
                if (abs_fast(slope) > max_step)
                    continue; // the two straddle a step
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

namespace {

// Union-find over patches with integer fringe-order offsets: a patch's values
// plus offset * period are in its root's frame.
struct OffsetForest {
    std::vector<std::int32_t> parent;
    std::vector<std::int32_t> offset;
    explicit OffsetForest(std::int32_t n)
        : parent(static_cast<std::size_t>(n)), offset(static_cast<std::size_t>(n), 0) {
        for (std::int32_t i = 0; i < n; ++i)
            parent[static_cast<std::size_t>(i)] = i;
    }
    // Root of x and x's offset to it.
    std::pair<std::int32_t, std::int32_t> find(std::int32_t x) {
        std::int32_t root = x, total = 0;
        while (parent[static_cast<std::size_t>(root)] != root) {
            total += offset[static_cast<std::size_t>(root)];
            root = parent[static_cast<std::size_t>(root)];
        }
        // Path compression, keeping offsets relative to the root.
        std::int32_t node = x, remaining = total;
        while (parent[static_cast<std::size_t>(node)] != root && node != root) {
            const std::int32_t up = parent[static_cast<std::size_t>(node)];
            const std::int32_t own = offset[static_cast<std::size_t>(node)];
            parent[static_cast<std::size_t>(node)] = root;
            offset[static_cast<std::size_t>(node)] = remaining;
            remaining -= own;
            node = up;
        }
        return {root, total};
    }
    // Patch q shifted by k periods continues patch p. False if that
    // contradicts earlier merges.
    bool join(std::int32_t p, std::int32_t q, std::int32_t k) {
        const auto [rp, op] = find(p);
        const auto [rq, oq] = find(q);
        if (rp == rq)
            return oq == k + op;
        parent[static_cast<std::size_t>(rq)] = rp;
        offset[static_cast<std::size_t>(rq)] = k + op - oq;
        return true;
    }
};

struct PatchLink {
    std::int32_t p = 0, q = 0; // p < q
    std::int32_t k = 0;        // q shifted by k periods continues p
    bool pass = false;
    friend bool operator<(const PatchLink& a, const PatchLink& b) {
        if (a.p != b.p)
            return a.p < b.p;
        if (a.q != b.q)
            return a.q < b.q;
        if (a.pass != b.pass)
            return a.pass > b.pass;
        return a.k < b.k;
    }
};

// A merge two patches' boundary links agree on: q shifted by k periods
// continues p, backed by `support` smooth links.
struct MergeCandidate {
    std::int32_t p, q, k, support;
};

// Each group's (forest root's) absolute fringe-order shift, or the reason it
// has none.
struct FringeOrders {
    std::vector<std::int32_t> shift;
    std::vector<std::uint8_t> flag;
};

constexpr std::int32_t kInvalid = -2, kUnvisited = -1;

// The inputs and per-pixel state the stages of unwrap_centerline share:
// `state` holds kInvalid, kUnvisited or the pixel's patch, `out` the value
// unwrapped within its patch (absolute after the last stage).
struct CenterlineUnwrap {
    int w;
    int h;
    std::int32_t count;
    const float* fraction;
    const float* other;
    const std::uint8_t* line;
    const CenterlineParams& params;
    float period;
    float inv;
    std::int32_t* state;
    float* out;

    // Wrapped difference f[j] - f[i], in periods, in [-0.5, 0.5].
    static float wrapped_in(const float* f, std::int32_t i, std::int32_t j) {
        const float d = f[j] - f[i];
        return d - round_fast(d);
    }
    // Neighbour of i one step in direction dir (0 left, 1 right, 2 up, 3 down), -1 outside.
    std::int32_t step(std::int32_t i, int dir) const {
        const int x = i % w, y = i / w;
        switch (dir) {
        case 0:
            return x > 0 ? i - 1 : -1;
        case 1:
            return x + 1 < w ? i + 1 : -1;
        case 2:
            return y > 0 ? i - w : -1;
        default:
            return y + 1 < h ? i + w : -1;
        }
    }
    bool usable(std::int32_t i) const { return i >= 0 && state[i] != kInvalid; }
    // Second difference of the link a -> b (direction dir) in f: how much the
    // step d differs from the steps just before and after it; -1 if neither exists.
    float curvature_of(const float* f, std::int32_t a, std::int32_t b, int dir, float d) const {
        float c = -1.0f;
        const std::int32_t before = step(a, dir ^ 1);
        if (usable(before))
            c = abs_fast(d - wrapped_in(f, before, a));
        const std::int32_t after = step(b, dir);
        if (usable(after))
            c = std::max(c, abs_fast(wrapped_in(f, b, after) - d));
        return c;
    }
    // A link is smooth if the wrapped step is small and steady in this axis's
    // phase and in the other axis's (a depth step moves both coordinates).
    bool smooth(std::int32_t a, std::int32_t b, int dir, float gate, float& d) const {
        d = wrapped_in(fraction, a, b);
        if (abs_fast(d) > params.jump_gate)
            return false;
        const float c = curvature_of(fraction, a, b, dir, d);
        if (c < 0.0f || c > gate)
            return false;
        if (other != nullptr) {
            const float od = wrapped_in(other, a, b);
            if (abs_fast(od) > params.jump_gate || curvature_of(other, a, b, dir, od) > gate)
                return false;
        }
        return true;
    }

    void mark_usable(const float* modulation, const std::uint8_t* sat) {
        for (std::int32_t i = 0; i < count; ++i) {
            const bool ok =
                modulation[i] >= params.min_modulation && (sat[i] & params.sat_bit) == 0;
            state[i] = ok ? kUnvisited : kInvalid;
        }
    }

    // 1. Patches: pixels joined by strictly smooth links, unwrapped relative
    //    to their first pixel (breadth first; `queue` is one int per pixel).
    //    Returns the number of patches.
    std::int32_t grow_patches(std::int32_t* queue) {
        std::int32_t patches = 0;
        for (std::int32_t seed = 0; seed < count; ++seed) {
            if (state[seed] != kUnvisited)
                continue;
            const std::int32_t id = patches++;
            state[seed] = id;
            out[seed] = fraction[seed] * period;
            std::int32_t head = 0, tail = 0;
            queue[tail++] = seed;
            while (head < tail) {
                const std::int32_t a = queue[head++];
                for (int dir = 0; dir < 4; ++dir) {
                    const std::int32_t b = step(a, dir);
                    float d = 0;
                    if (b < 0 || state[b] != kUnvisited || !smooth(a, b, dir, params.patch_gate, d))
                        continue;
                    state[b] = id;
                    const float pw = fraction[b] * period;
                    out[b] = pw + round_fast((out[a] - pw) * inv) * period;
                    queue[tail++] = b;
                }
            }
        }
        return patches;
    }

    // 2a. Every link (right and down) between two patches, with whether it is
    //     smooth under the merge gate and the offset it implies; sorted so
    //     that each pair's links are adjacent.
    std::vector<PatchLink> boundary_links() const {
        std::vector<PatchLink> links;
        for (std::int32_t a = 0; a < count; ++a) {
            if (state[a] < 0)
                continue;
            for (int dir : {1, 3}) {
                const std::int32_t b = step(a, dir);
                if (b < 0 || state[b] < 0 || state[b] == state[a])
                    continue;
                PatchLink link;
                float d = 0;
                link.pass = smooth(a, b, dir, params.merge_gate, d);
                // q shifted by k continues p at this link.
                const float k = round_fast((out[a] + d * period - out[b]) * inv);
                link.p = state[a];
                link.q = state[b];
                link.k = static_cast<std::int32_t>(k);
                if (link.p > link.q) {
                    std::swap(link.p, link.q);
                    link.k = -link.k;
                }
                links.push_back(link);
            }
        }
        std::sort(links.begin(), links.end());
        return links;
    }

    // 3. Seeds: pixels lit by the centerline whose wrapped position matches
    //    the line.
    bool on_line(std::int32_t i) const {
        if (line[i] == 0 || state[i] < 0)
            return false;
        const double position = params.position;
        const double period_d = static_cast<double>(period);
        const double reach = params.half_width + 1.0;
        double offset = static_cast<double>(fraction[i]) * period_d - position;
        offset -= period_d * std::floor(offset / period_d + 0.5);
        return std::abs(offset) <= reach;
    }
    // Seeds in runs (at least two such 8-neighbours), so that a stray bright
    // pixel cannot vote; each votes for its group's fringe order. Sorted
    // (root, fringe-order shift) pairs.
    std::vector<std::pair<std::int32_t, std::int32_t>> line_votes(OffsetForest& forest) const {
        const double position = params.position;
        const double period_d = static_cast<double>(period);
        std::vector<std::pair<std::int32_t, std::int32_t>> votes;
        for (std::int32_t i = 0; i < count; ++i) {
            if (!on_line(i))
                continue;
            const int x = i % w, y = i / w;
            int neighbours = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    if ((dx == 0 && dy == 0) || x + dx < 0 || x + dx >= w || y + dy < 0 ||
                        y + dy >= h)
                        continue;
                    neighbours += on_line(i + dy * w + dx) ? 1 : 0;
                }
            if (neighbours < 2)
                continue;
            const auto [root, offset] = forest.find(state[i]);
            const double value = static_cast<double>(out[i]) + offset * period_d;
            votes.emplace_back(
                root, static_cast<std::int32_t>(std::lround((position - value) / period_d)));
        }
        std::sort(votes.begin(), votes.end());
        return votes;
    }

    // 4. Absolute coordinates for groups with a centerline; the rest has no cue.
    void apply_orders(OffsetForest& forest, const FringeOrders& orders, std::uint8_t* mask) {
        for (std::int32_t i = 0; i < count; ++i) {
            if (state[i] < 0) {
                out[i] = kNaN; // flagged already (low modulation or saturated)
                continue;
            }
            const auto [root, offset] = forest.find(state[i]);
            const std::uint8_t f = orders.flag[static_cast<std::size_t>(root)];
            if (f != 0) {
                out[i] = kNaN;
                mask[i] = static_cast<std::uint8_t>(mask[i] | f);
            } else {
                out[i] +=
                    static_cast<float>(offset + orders.shift[static_cast<std::size_t>(root)]) *
                    period;
                if (out[i] < -1.5f || out[i] > params.highest) {
                    out[i] = kNaN;
                    mask[i] = static_cast<std::uint8_t>(mask[i] | kDecodeOutOfRange);
                }
            }
        }
    }
};

// 2b. Two patches of one surface (split where the phase is noisy or curves)
//     share a boundary whose links are mostly smooth and agree on the offset;
//     at an occlusion edge most links jump and only a few look smooth by
//     chance. The pairs that pass, best supported first.
std::vector<MergeCandidate> agreed_merges(const std::vector<PatchLink>& links,
                                          const CenterlineParams& params) {
    std::vector<MergeCandidate> candidates;
    for (std::size_t s = 0; s < links.size();) {
        std::size_t e = s;
        int total = 0, passing = 0, best = 0;
        std::int32_t best_k = 0;
        while (e < links.size() && links[e].p == links[s].p && links[e].q == links[s].q) {
            std::size_t f = e;
            while (f < links.size() && links[f].p == links[e].p && links[f].q == links[e].q &&
                   links[f].pass == links[e].pass && links[f].k == links[e].k)
                ++f;
            const int n = static_cast<int>(f - e);
            total += n;
            if (links[e].pass) {
                passing += n;
                if (n > best) {
                    best = n;
                    best_k = links[e].k;
                }
            }
            e = f;
        }
        if (passing >= params.min_links && 2 * passing >= total && 5 * best >= 4 * passing)
            candidates.push_back({links[s].p, links[s].q, best_k, best});
        s = e;
    }
    std::stable_sort(
        candidates.begin(), candidates.end(),
        [](const MergeCandidate& x, const MergeCandidate& y) { return x.support > y.support; });
    return candidates;
}

// 3b. Each group's fringe order from its sorted votes: the most common one
//     when it has `min_votes` and a 2/3 majority; disputed when enough votes
//     disagree; no cue without votes.
FringeOrders count_votes(const std::vector<std::pair<std::int32_t, std::int32_t>>& votes,
                         std::int32_t patches, const CenterlineParams& params) {
    FringeOrders orders{std::vector<std::int32_t>(static_cast<std::size_t>(patches), 0),
                        std::vector<std::uint8_t>(static_cast<std::size_t>(patches), kDecodeNoCue)};
    for (std::size_t s = 0; s < votes.size();) {
        const std::int32_t root = votes[s].first;
        std::size_t e = s;
        int total = 0, best = 0;
        std::int32_t best_k = 0;
        while (e < votes.size() && votes[e].first == root) {
            std::size_t f = e;
            while (f < votes.size() && votes[f] == votes[e])
                ++f;
            const int n = static_cast<int>(f - e);
            total += n;
            if (n > best) {
                best = n;
                best_k = votes[e].second;
            }
            e = f;
        }
        if (best >= params.min_votes && 3 * best >= 2 * total) {
            orders.shift[static_cast<std::size_t>(root)] = best_k;
            orders.flag[static_cast<std::size_t>(root)] = 0;
        } else if (total >= params.min_votes) {
            orders.flag[static_cast<std::size_t>(root)] = kDecodeUnwrapInconsistent;
        }
        s = e;
    }
    return orders;
}

} // namespace

void unwrap_centerline(Size size, const float* fraction, const float* other,
                       const float* modulation, const std::uint8_t* sat, const std::uint8_t* line,
                       const CenterlineParams& params, std::int32_t* state, std::int32_t* next,
                       float* out, std::uint8_t* mask) {
    CenterlineUnwrap u{size.width,
                       size.height,
                       static_cast<std::int32_t>(size.area()),
                       fraction,
                       other,
                       line,
                       params,
                       params.period,
                       1.0f / params.period,
                       state,
                       out};
    u.mark_usable(modulation, sat);
    const std::int32_t patches = u.grow_patches(next);
    OffsetForest forest(patches);
    for (const MergeCandidate& c : agreed_merges(u.boundary_links(), params))
        forest.join(c.p, c.q, c.k);
    const FringeOrders orders = count_votes(u.line_votes(forest), patches, params);
    u.apply_orders(forest, orders, mask);
}

} // namespace fpp::detail
