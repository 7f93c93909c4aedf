// Smoothing of a flat board's phase map (see phase_smoothing.hpp).

#include "phase_smoothing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace fpp::calib {

namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
} // namespace

// Quadratic Savitzky-Golay smoothing of a flat board's phase map, separable:
// rows, then columns. Weights of the centre value of a quadratic fit to
// 2r + 1 equally spaced samples: (3(3r^2 + 3r - 1) - 15 k^2) / ((2r-1)(2r+1)(2r+3)).
// A sample is smoothed only when its whole window is finite; else it keeps
// its value.
void smooth_phase(Image<float>& phase, int r, ThreadPool& pool) {
    if (r <= 0)
        return;
    const int w = phase.width(), h = phase.height();
    std::vector<double> weight(static_cast<std::size_t>(2 * r + 1));
    const double den = double(2 * r - 1) * double(2 * r + 1) * double(2 * r + 3);
    for (int k = -r; k <= r; ++k)
        weight[static_cast<std::size_t>(k + r)] =
            (3.0 * (3.0 * r * r + 3.0 * r - 1.0) - 15.0 * k * k) / den;
    // Pass 1 along rows into `rows` (NaN where the window is incomplete).
    Image<float> rows(phase.size(), 1, kNaN);
    pool.parallel_for(h, 8, [&](int y0, int y1, int) {
        for (int y = y0; y < y1; ++y) {
            const float* in = phase.row(y);
            float* out = rows.row(y);
            for (int x = r; x < w - r; ++x) {
                double sum = 0;
                for (int k = -r; k <= r; ++k)
                    sum += weight[static_cast<std::size_t>(k + r)] * double(in[x + k]);
                out[x] = static_cast<float>(sum); // NaN if any sample is NaN
            }
        }
    });
    // Pass 2 along columns of `rows`, into phase where complete.
    pool.parallel_for(h, 8, [&](int y0, int y1, int) {
        for (int y = std::max(y0, r); y < std::min(y1, h - r); ++y)
            for (int x = r; x < w - r; ++x) {
                double sum = 0;
                for (int k = -r; k <= r; ++k)
                    sum += weight[static_cast<std::size_t>(k + r)] * double(rows.at(x, y + k));
                if (std::isfinite(sum))
                    phase.at(x, y) = static_cast<float>(sum);
            }
    });
}

} // namespace fpp::calib
