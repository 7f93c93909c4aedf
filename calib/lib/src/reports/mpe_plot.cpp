// A figure's values against its MPE band (see the header).

#include "fpp/calib/mpe_plot.hpp"

#include "fpp/calib/plots.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace fpp::calib {

namespace {

const cv::Scalar kBlack(0, 0, 0), kGrey(150, 150, 150), kGrid(225, 225, 225);
const cv::Scalar kBand(200, 235, 200), kInside(150, 90, 30), kOutside(40, 40, 210);
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

void label(cv::Mat& image, const std::string& s, cv::Point at, double size = 0.45) {
    cv::putText(image, s, at, kFont, size, kBlack, 1, cv::LINE_AA);
}

int text_width(const std::string& s, double size) {
    int baseline = 0;
    return cv::getTextSize(s, kFont, size, 1, &baseline).width;
}

} // namespace

cv::Mat mpe_plot(const std::vector<double>& values, const std::vector<std::string>& labels,
                 std::optional<double> mpe, bool signed_figure, const std::string& x_label,
                 const std::string& y_label, const std::string& title) {
    const int width = 820, height = 480, left = 90, right = 30, top = 60, bottom = 70;
    const int plot_w = width - left - right, plot_h = height - top - bottom;
    cv::Mat canvas(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    // The scale holds every value and the band, with a margin.
    double reach = mpe ? *mpe : 0;
    for (const double v : values)
        if (std::isfinite(v))
            reach = std::max(reach, std::abs(v));
    const double top_value = nice_ceil(std::max(reach * 1.15, 1e-4));
    const double lo = signed_figure ? -top_value : 0, hi = top_value;
    auto y_of = [&](double v) {
        return top +
               static_cast<int>(std::lround((hi - std::clamp(v, lo, hi)) / (hi - lo) * plot_h));
    };
    const std::size_t n = std::max<std::size_t>(values.size(), 1);
    auto x_of = [&](std::size_t k) {
        return left + static_cast<int>(std::lround((double(k) + 0.5) / double(n) * plot_w));
    };
    if (mpe)
        cv::rectangle(canvas, {left, y_of(*mpe)}, {left + plot_w, y_of(signed_figure ? -*mpe : 0)},
                      kBand, cv::FILLED);
    for (int t = 0; t <= 4; ++t) {
        const double v = lo + (hi - lo) * t / 4;
        const int y = y_of(v);
        cv::line(canvas, {left, y}, {left + plot_w, y}, std::abs(v) < 1e-12 ? kGrey : kGrid);
        const std::string text = fixed_text(v, 4);
        label(canvas, text, {left - 8 - text_width(text, 0.4), y + 5}, 0.4);
    }
    cv::rectangle(canvas, {left, top}, {left + plot_w, top + plot_h}, kBlack);
    for (std::size_t k = 0; k < values.size(); ++k) {
        const double v = values[k];
        if (!std::isfinite(v))
            continue;
        const bool outside = mpe && std::abs(v) > *mpe;
        const cv::Point at(x_of(k), y_of(v));
        cv::line(canvas, {at.x, y_of(signed_figure ? 0.0 : lo)}, at, outside ? kOutside : kInside,
                 2, cv::LINE_AA);
        cv::circle(canvas, at, 5, outside ? kOutside : kInside, cv::FILLED, cv::LINE_AA);
        if (k < labels.size() && values.size() <= 40)
            label(canvas, labels[k], {at.x - text_width(labels[k], 0.4) / 2, top + plot_h + 18},
                  0.4);
    }
    label(canvas, x_label, {left + plot_w / 2 - text_width(x_label, 0.45) / 2, height - 20});
    label(canvas, y_label, {8, top - 12}, 0.42);
    label(canvas, title, {left, 28}, 0.55);
    const std::string legend =
        mpe ? "green: within the MPE " + fixed_text(*mpe, 4) + " mm; red: outside"
            : "no MPE given: no verdict";
    label(canvas, legend, {left + plot_w - text_width(legend, 0.42), top - 12}, 0.42);
    return canvas;
}

} // namespace fpp::calib
