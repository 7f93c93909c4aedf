#include "blur.hpp"

#include <algorithm>
#include <cmath>

namespace fpp::sim::detail {

std::vector<float> gaussian_kernel(double sigma) {
    const int r = std::max(1, static_cast<int>(std::ceil(3.5 * sigma)));
    std::vector<double> w(static_cast<std::size_t>(2 * r + 1));
    double sum = 0;
    for (int k = -r; k <= r; ++k) {
        const double v = std::exp(-0.5 * (k * k) / (sigma * sigma));
        w[static_cast<std::size_t>(k + r)] = v;
        sum += v;
    }
    std::vector<float> out(w.size());
    for (std::size_t i = 0; i < w.size(); ++i)
        out[i] = static_cast<float>(w[i] / sum);
    return out;
}

void gaussian_blur(float* image, int W, int H, double sigma, Border border, ThreadPool& pool,
                   std::vector<float>& scratch) {
    if (!(sigma > 0) || W <= 0 || H <= 0)
        return;
    const std::vector<float> kernel = gaussian_kernel(sigma);
    const int r = static_cast<int>(kernel.size() / 2);
    // scratch = the horizontally blurred image, then one padded row per worker.
    const std::size_t area = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
    const std::size_t padded_width = static_cast<std::size_t>(W + 2 * r);
    scratch.resize(area + static_cast<std::size_t>(pool.size()) * padded_width);
    float* tmp = scratch.data();
    auto row = [W](float* base, int y) { return base + static_cast<std::size_t>(y) * W; };
    // About eight chunks of rows per worker.
    const int grain = std::max(1, H / (8 * pool.size()));

    // Horizontal pass into tmp, through a padded copy of each row.
    pool.parallel_for(H, grain, [&](int y0, int y1, int worker) {
        float* padded = tmp + area + static_cast<std::size_t>(worker) * padded_width;
        for (int y = y0; y < y1; ++y) {
            const float* in = row(image, y);
            for (int x = 0; x < W + 2 * r; ++x) {
                const int sx = x - r;
                padded[x] = (sx >= 0 && sx < W)      ? in[sx]
                            : border == Border::zero ? 0.0f
                                                     : in[std::clamp(sx, 0, W - 1)];
            }
            float* out = row(tmp, y);
            std::fill(out, out + W, 0.0f);
            for (int k = 0; k <= 2 * r; ++k) {
                const float wk = kernel[static_cast<std::size_t>(k)];
                const float* src = padded + k;
                for (int x = 0; x < W; ++x)
                    out[x] += wk * src[x];
            }
        }
    });
    // Vertical pass back into the image.
    pool.parallel_for(H, grain, [&](int y0, int y1, int) {
        for (int y = y0; y < y1; ++y) {
            float* out = row(image, y);
            std::fill(out, out + W, 0.0f);
            for (int k = -r; k <= r; ++k) {
                int sy = y + k;
                if (sy < 0 || sy >= H) {
                    if (border == Border::zero)
                        continue;
                    sy = std::clamp(sy, 0, H - 1);
                }
                const float wk = kernel[static_cast<std::size_t>(k + r)];
                const float* src = row(tmp, sy);
                for (int x = 0; x < W; ++x)
                    out[x] += wk * src[x];
            }
        }
    });
}

} // namespace fpp::sim::detail
