// Bright board samples of a calibration pose (see fpp/calib/board_samples.hpp).

#include "fpp/calib/board_samples.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fpp::calib {

namespace {

// Separable minimum filter of a 0/1 mask over a (2r + 1)^2 window; outside
// the image counts as 0.
void erode(Image<std::uint8_t>& mask, int r) {
    if (r <= 0)
        return;
    const int w = mask.width(), h = mask.height();
    Image<std::uint8_t> rows(mask.size());
    std::vector<int> left(static_cast<std::size_t>(w)), up(static_cast<std::size_t>(h));
    for (int y = 0; y < h; ++y) {
        // Run length of set pixels ending at x, then at least r + 1 on both sides.
        const std::uint8_t* in = mask.row(y);
        std::uint8_t* out = rows.row(y);
        int run = 0;
        for (int x = 0; x < w; ++x) {
            run = in[x] ? run + 1 : 0;
            left[std::size_t(x)] = run;
        }
        run = 0;
        for (int x = w - 1; x >= 0; --x) {
            run = in[x] ? run + 1 : 0;
            out[x] = (left[std::size_t(x)] > r && run > r) ? 1 : 0;
        }
    }
    for (int x = 0; x < w; ++x) {
        int run = 0;
        for (int y = 0; y < h; ++y) {
            run = rows.at(x, y) ? run + 1 : 0;
            up[std::size_t(y)] = run;
        }
        run = 0;
        for (int y = h - 1; y >= 0; --y) {
            run = rows.at(x, y) ? run + 1 : 0;
            mask.at(x, y) = (up[std::size_t(y)] > r && run > r) ? 1 : 0;
        }
    }
}

} // namespace

void BrightBoardOptions::validate() const {
    if (!(min_modulation_fraction > 0 && min_modulation_fraction < 1))
        throw std::invalid_argument(
            "bright board option min_modulation_fraction: must be in (0, 1)");
    if (erosion_px < 0 || erosion_px > 50)
        throw std::invalid_argument("bright board option erosion_px: must be in [0, 50]");
}

Image<std::uint8_t> bright_board_mask(const DecodeResult& decoded, bool need_y,
                                      const BrightBoardOptions& options) {
    options.validate();
    if (need_y && decoded.proj_y.empty())
        throw std::invalid_argument("bright board mask: the capture decodes no projector row");
    const Size size = decoded.proj_x.size();
    Image<std::uint8_t> mask(size);
    if (decoded.modulation.size() != size)
        return mask;
    const std::size_t n = size.area();
    const float* px = decoded.proj_x.data();
    const float* py = need_y ? decoded.proj_y.data() : nullptr;
    const float* b = decoded.modulation.data();
    const auto decoded_at = [&](std::size_t i) {
        return std::isfinite(px[i]) && (!py || std::isfinite(py[i])) && std::isfinite(b[i]);
    };
    std::vector<float> levels;
    const std::size_t stride = std::max<std::size_t>(1, n / 200000);
    for (std::size_t i = 0; i < n; i += stride)
        if (decoded_at(i))
            levels.push_back(b[i]);
    if (levels.empty())
        return mask;
    const auto k = static_cast<std::ptrdiff_t>(0.9 * double(levels.size() - 1));
    std::nth_element(levels.begin(), levels.begin() + k, levels.end());
    const double limit = options.min_modulation_fraction * double(levels[std::size_t(k)]);
    for (std::size_t i = 0; i < n; ++i)
        mask.data()[i] = decoded_at(i) && double(b[i]) >= limit ? 1 : 0;
    erode(mask, options.erosion_px);
    return mask;
}

double bright_fraction(const DecodeResult& decoded, const Image<std::uint8_t>& mask) {
    std::size_t decoded_pixels = 0, kept = 0;
    for (std::size_t i = 0; i < mask.pixel_count(); ++i) {
        decoded_pixels += std::isfinite(decoded.proj_x.data()[i]) ? 1 : 0;
        kept += mask.data()[i] ? 1 : 0;
    }
    return decoded_pixels ? double(kept) / double(decoded_pixels) : 0.0;
}

void dense_projector_samples(const DecodeResult& decoded, const Image<std::uint8_t>& mask, int step,
                             std::vector<Vec2>& camera, std::vector<Vec2>& projector) {
    camera.clear();
    projector.clear();
    if (decoded.proj_y.empty() || step < 1)
        return;
    const Size size = mask.size();
    for (int v = step / 2; v < size.height; v += step)
        for (int u = step / 2; u < size.width; u += step)
            if (mask.at(u, v)) {
                camera.push_back({double(u), double(v)});
                projector.push_back(
                    {double(decoded.proj_x.at(u, v)), double(decoded.proj_y.at(u, v))});
            }
}

} // namespace fpp::calib
