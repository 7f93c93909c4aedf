// The detector stage of find_checkerboard: OpenCV's finders on a reduced,
// shading-divided copy of the texture (corner_detect.hpp).
//
// Measured on simulated white frames at 1600 x 1200 (15 x 11 board of 12 mm
// tilted 35-45 degrees and pushed into the image's corners; paper rig with
// effects): where the classic finder with adaptive thresholds failed it took
// 0.3-2.4 s on the 800 x 600 copy and 5-6 s on the image itself (6 block
// sizes at 8 dilations, each grouping every quad), and the sector finder's
// exhaustive search with upsampling took 1.5 s on the full image; a board
// partly out of the projector's light cost 7.8 s a texture (bench_corners:
// 22x a frontal pose), and the adaptive classic finder returned a board with
// a wrong corner for 9 of 72 such poses. On the divided copy the classic
// finder takes 5-25 ms and the default sector search 0.05-0.3 s; every
// wholly lit board of 108 poses is found, a tilted one in 0.7-1.05x a
// frontal pose's time, and a partly lit one given up in 0.6x.

#include "corner_detect.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace fpp::calib::detail {

namespace {

// The local white level may not fall below this fraction of the image's
// bright level (its 99.5 % quantile): unlit background stays dark instead of
// being stretched into noise.
constexpr float kWhiteFloor = 0.25f;

float bright_level(const cv::Mat& image) {
    std::vector<float> sample;
    const std::size_t n = image.total();
    const std::size_t stride = std::max<std::size_t>(1, n / 100000);
    const auto* p = image.ptr<float>(0);
    for (std::size_t i = 0; i < n; i += stride)
        sample.push_back(p[i]);
    if (sample.empty())
        return 1;
    const auto k = static_cast<std::ptrdiff_t>(0.995 * static_cast<double>(sample.size() - 1));
    std::nth_element(sample.begin(), sample.begin() + k, sample.end());
    return std::max(sample[static_cast<std::size_t>(k)], 1e-6f);
}

} // namespace

int detector_factor(Size texture) {
    return std::max(1,
                    (std::max(texture.width, texture.height) + kDetectorSide - 1) / kDetectorSide);
}

cv::Mat detector_image(const Image<float>& texture, int factor) {
    const int w = texture.width() / factor, h = texture.height() / factor;
    if (w < 1 || h < 1)
        return {};
    cv::Mat full(texture.height(), texture.width(), CV_32F, const_cast<float*>(texture.data()));
    cv::Mat reduced;
    // Cropped to whole blocks: pixel (x, y) of the copy is the mean of the
    // texture's block centred on ((x + 0.5) f - 0.5, (y + 0.5) f - 0.5).
    cv::resize(full(cv::Rect(0, 0, w * factor, h * factor)), reduced, cv::Size(w, h), 0, 0,
               cv::INTER_AREA);
    cv::patchNaNs(reduced, 0.0);
    // The window spans a square of any board the finders can tell at this
    // size, so that it always holds white paper.
    const int window = std::max(3, std::min(w, h) / 8) | 1;
    cv::Mat white;
    cv::dilate(reduced, white, cv::getStructuringElement(cv::MORPH_RECT, {window, window}));
    cv::blur(white, white, {window, window});
    const float floor = kWhiteFloor * bright_level(reduced);
    cv::Mat out(h, w, CV_8U);
    for (int y = 0; y < h; ++y) {
        const auto* v = reduced.ptr<float>(y);
        const auto* wl = white.ptr<float>(y);
        auto* o = out.ptr<std::uint8_t>(y);
        for (int x = 0; x < w; ++x)
            o[x] = cv::saturate_cast<std::uint8_t>(255.0f * v[x] / std::max(wl[x], floor));
    }
    return out;
}

bool run_finder(const cv::Mat& image8, int factor, int columns, int rows, Finder finder,
                std::vector<cv::Point2f>& found) {
    found.clear();
    if (image8.empty())
        return false;
    const cv::Size pattern(columns, rows);
    const bool ok =
        finder == Finder::sector
            ? cv::findChessboardCornersSB(image8, pattern, found, 0)
            : cv::findChessboardCorners(image8, pattern, found,
                                        cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK);
    if (!ok || found.size() != static_cast<std::size_t>(columns * rows))
        return false;
    const float f = static_cast<float>(factor);
    for (cv::Point2f& p : found)
        p = {(p.x + 0.5f) * f - 0.5f, (p.y + 0.5f) * f - 0.5f};
    return true;
}

} // namespace fpp::calib::detail
