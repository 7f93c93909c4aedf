// Report figures: signed maps and histograms.

#include "fpp/calib/plots.hpp"

#include "fpp/false_colour.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace fpp::calib {

namespace {

const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kNoValue(90, 90, 90);
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

void text(cv::Mat& image, const std::string& s, cv::Point at, double size = 0.45,
          const cv::Scalar& colour = kBlack) {
    cv::putText(image, s, at, kFont, size, colour, 1, cv::LINE_AA);
}

int text_width(const std::string& s, double size = 0.45) {
    int baseline = 0;
    return cv::getTextSize(s, kFont, size, 1, &baseline).width;
}

// Fewest decimals (up to 6) that print every value exactly.
int decimals_for(std::span<const double> values) {
    for (int d = 0; d < 6; ++d) {
        const double m = std::pow(10.0, d);
        bool exact = true;
        for (double v : values)
            exact = exact &&
                    std::abs(std::round(v * m) - v * m) < 1e-6 * std::max(1.0, std::abs(v * m));
        if (exact)
            return d;
    }
    return 6;
}

} // namespace

std::string fixed_text(double value, int digits) {
    if (!std::isfinite(value))
        return "-";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", digits, value);
    return buf;
}

double nice_ceil(double value) {
    if (!(value > 0) || !std::isfinite(value))
        return 1;
    const double decade = std::pow(10.0, std::floor(std::log10(value)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * decade >= value * (1 - 1e-12))
            return m * decade;
    return 10 * decade;
}

double symmetric_limit(std::span<const double> values, double quantile, double fallback) {
    std::vector<double> magnitudes;
    magnitudes.reserve(values.size());
    for (double v : values)
        if (std::isfinite(v))
            magnitudes.push_back(std::abs(v));
    if (magnitudes.empty())
        return fallback;
    const auto k = static_cast<std::size_t>(std::clamp(quantile, 0.0, 1.0) *
                                            static_cast<double>(magnitudes.size() - 1));
    std::nth_element(magnitudes.begin(), magnitudes.begin() + static_cast<std::ptrdiff_t>(k),
                     magnitudes.end());
    const double q = magnitudes[k];
    return q > 0 ? nice_ceil(q) : fallback;
}

cv::Vec3b diverging_colour(double t) {
    // RdBu anchors as RGB from -1 (blue) to +1 (red).
    static constexpr std::array<std::array<double, 3>, 5> anchors = {
        {{5, 48, 97}, {67, 147, 195}, {247, 247, 247}, {214, 96, 77}, {103, 0, 31}}};
    if (!std::isfinite(t))
        t = 0;
    const double x = (std::clamp(t, -1.0, 1.0) + 1) * 2; // 0..4
    const auto i = static_cast<std::size_t>(std::min(3.0, std::floor(x)));
    const double f = x - static_cast<double>(i);
    cv::Vec3b bgr;
    for (int c = 0; c < 3; ++c) {
        const double v = anchors[i][static_cast<std::size_t>(c)] * (1 - f) +
                         anchors[i + 1][static_cast<std::size_t>(c)] * f;
        bgr[2 - c] = static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
    }
    return bgr;
}

cv::Mat map_figure(const Image<float>& values, float lo, float hi, const std::string& title) {
    const Image<std::uint8_t> small = false_colour(values, lo, hi);
    // A coarse map (a few cells per side) enlarged by whole pixels.
    const int factor = std::max(1, 400 / std::max(1, values.width()));
    const int w = values.width() * factor, h = values.height() * factor;
    const auto rgb_at = [&](int x, int y) { return &small.at(x / factor, y / factor, 0); };
    const int bar = 24, margin = 90, top = 30;
    cv::Mat out(h + top + 10, w + margin + bar, CV_8UC3, cv::Scalar(255, 255, 255));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::uint8_t* c = rgb_at(x, y);
            out.at<cv::Vec3b>(y + top, x) = cv::Vec3b(c[2], c[1], c[0]);
        }
    for (int y = 0; y < h; ++y) {
        std::uint8_t c[3];
        ramp_colour(1.0f - static_cast<float>(y) / static_cast<float>(std::max(h - 1, 1)), c);
        cv::line(out, {w + 10, y + top}, {w + 10 + bar, y + top}, cv::Scalar(c[2], c[1], c[0]));
    }
    for (int t = 0; t <= 4; ++t) {
        const int y = top + (h - 1) * (4 - t) / 4;
        const double v = double(lo) + double(hi - lo) * t / 4;
        cv::putText(out, fixed_text(v, 4), {w + 14 + bar, y + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.4,
                    {0, 0, 0}, 1, cv::LINE_AA);
    }
    cv::putText(out, title, {4, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0}, 1, cv::LINE_AA);
    return out;
}

cv::Mat signed_map_figure(const Image<float>& values, double limit, const std::string& title,
                          const std::string& unit) {
    if (values.channels() != 1 || values.empty())
        throw std::invalid_argument("signed_map_figure: 1-channel, non-empty image expected");
    if (!(limit > 0))
        limit = 1;
    cv::Mat colours(values.height(), values.width(), CV_8UC3);
    for (int y = 0; y < values.height(); ++y) {
        const float* in = values.row(y);
        auto* out = colours.ptr<cv::Vec3b>(y);
        for (int x = 0; x < values.width(); ++x) {
            const double v = double(in[x]);
            out[x] = std::isfinite(v) ? diverging_colour(v / limit)
                                      : cv::Vec3b(static_cast<std::uint8_t>(kNoValue[0]),
                                                  static_cast<std::uint8_t>(kNoValue[1]),
                                                  static_cast<std::uint8_t>(kNoValue[2]));
        }
    }
    cv::Mat map;
    if (values.width() > 1000) {
        const double scale = 1000.0 / values.width();
        cv::resize(colours, map, cv::Size(), scale, scale, cv::INTER_AREA);
    } else if (values.width() < 480) {
        const int factor = (480 + values.width() - 1) / values.width();
        cv::resize(colours, map, cv::Size(), factor, factor, cv::INTER_NEAREST);
    } else {
        map = colours;
    }
    const int top = 40, bottom = 30, left = 10, bar_panel = 150;
    const int plot_h = std::max(map.rows, 260);
    cv::Mat canvas(top + plot_h + bottom, left + map.cols + bar_panel, CV_8UC3, kWhite);
    map.copyTo(canvas(cv::Rect(left, top, map.cols, map.rows)));
    text(canvas, title, {left, 25}, 0.55);
    text(canvas, "grey: no value", {left, top + map.rows + 20}, 0.4);

    // Colour bar: +limit at the top, -limit at the bottom.
    const int bar_x = left + map.cols + 25, bar_w = 22, bar_top = top + 20;
    const int bar_h = plot_h - 40;
    for (int r = 0; r < bar_h; ++r) {
        const double t = 1 - 2 * (r + 0.5) / bar_h;
        const cv::Vec3b c = diverging_colour(t);
        cv::line(canvas, {bar_x, bar_top + r}, {bar_x + bar_w - 1, bar_top + r},
                 cv::Scalar(c[0], c[1], c[2]));
    }
    cv::rectangle(canvas, {bar_x, bar_top}, {bar_x + bar_w - 1, bar_top + bar_h - 1}, kBlack);
    const std::array<double, 5> ticks = {limit, limit / 2, 0, -limit / 2, -limit};
    const int digits = decimals_for(ticks);
    for (std::size_t k = 0; k < ticks.size(); ++k) {
        const int y =
            bar_top + static_cast<int>(std::lround(static_cast<double>(k) / 4 * (bar_h - 1)));
        cv::line(canvas, {bar_x + bar_w, y}, {bar_x + bar_w + 5, y}, kBlack);
        char label[64];
        std::snprintf(label, sizeof label, ticks[k] > 0 ? "%+.*f" : "%.*f", digits, ticks[k]);
        text(canvas, label, {bar_x + bar_w + 8, y + 5}, 0.42);
    }
    text(canvas, unit, {bar_x, bar_top - 8}, 0.45);
    return canvas;
}

cv::Mat histogram_figure(const std::vector<HistogramSeries>& series, double lo, double hi,
                         const std::string& x_label, const std::string& title) {
    if (!(hi > lo))
        hi = lo + 1;
    constexpr int kBins = 80;
    const int width = 820, height = 500, left = 70, right = 20, top = 50, bottom = 60;
    const int plot_w = width - left - right, plot_h = height - top - bottom;
    const std::array<cv::Scalar, 4> colours = {cv::Scalar(200, 110, 30), cv::Scalar(30, 120, 235),
                                               cv::Scalar(60, 170, 60), cv::Scalar(150, 60, 170)};
    std::vector<std::array<double, kBins>> percent(series.size());
    std::vector<std::size_t> outside(series.size(), 0), counts(series.size(), 0);
    std::vector<double> rms(series.size(), 0);
    double peak = 1e-9;
    for (std::size_t s = 0; s < series.size(); ++s) {
        std::array<double, kBins>& bins = percent[s];
        bins.fill(0);
        double sum2 = 0;
        for (double v : series[s].values) {
            if (!std::isfinite(v))
                continue;
            ++counts[s];
            sum2 += v * v;
            const double f = (v - lo) / (hi - lo);
            if (f < 0 || f > 1) {
                ++outside[s];
                continue;
            }
            bins[static_cast<std::size_t>(std::min(kBins - 1, static_cast<int>(f * kBins)))] += 1;
        }
        rms[s] = counts[s] ? std::sqrt(sum2 / static_cast<double>(counts[s])) : 0;
        for (double& b : bins) {
            b = counts[s] ? 100 * b / static_cast<double>(counts[s]) : 0;
            peak = std::max(peak, b);
        }
    }
    const double y_max = nice_ceil(peak * 1.1);
    cv::Mat canvas(height, width, CV_8UC3, kWhite);
    auto x_of = [&](double v) {
        return left + static_cast<int>(std::lround((v - lo) / (hi - lo) * plot_w));
    };
    auto y_of = [&](double p) {
        return top + plot_h - static_cast<int>(std::lround(p / y_max * plot_h));
    };
    // Filled bars, blended so that overlapping series stay visible; outlines on top.
    for (std::size_t s = 0; s < series.size(); ++s) {
        cv::Mat layer = canvas.clone();
        const cv::Scalar colour = colours[s % colours.size()];
        for (int b = 0; b < kBins; ++b) {
            const double p = percent[s][static_cast<std::size_t>(b)];
            if (p <= 0)
                continue;
            const int x0 = left + b * plot_w / kBins, x1 = left + (b + 1) * plot_w / kBins;
            cv::rectangle(layer, {x0, y_of(p)}, {x1, top + plot_h}, colour, cv::FILLED);
        }
        cv::addWeighted(layer, 0.35, canvas, 0.65, 0, canvas);
    }
    for (std::size_t s = 0; s < series.size(); ++s) {
        const cv::Scalar colour = colours[s % colours.size()];
        cv::Point previous(left, top + plot_h);
        for (int b = 0; b < kBins; ++b) {
            const int y = y_of(percent[s][static_cast<std::size_t>(b)]);
            const int x0 = left + b * plot_w / kBins, x1 = left + (b + 1) * plot_w / kBins;
            cv::line(canvas, previous, {x0, y}, colour, 2, cv::LINE_AA);
            cv::line(canvas, {x0, y}, {x1, y}, colour, 2, cv::LINE_AA);
            previous = {x1, y};
        }
        cv::line(canvas, previous, {left + plot_w, top + plot_h}, colour, 2, cv::LINE_AA);
    }
    // Axes and ticks.
    cv::line(canvas, {left, top + plot_h}, {left + plot_w, top + plot_h}, kBlack);
    cv::line(canvas, {left, top}, {left, top + plot_h}, kBlack);
    const double x_step = nice_ceil((hi - lo) / 8);
    std::vector<double> x_ticks;
    for (double v = std::ceil(lo / x_step) * x_step; v <= hi + 1e-9 * x_step; v += x_step)
        x_ticks.push_back(std::abs(v) < 1e-12 * x_step ? 0 : v);
    const int x_digits = decimals_for(x_ticks);
    for (double v : x_ticks) {
        const int x = x_of(v);
        cv::line(canvas, {x, top + plot_h}, {x, top + plot_h + 5}, kBlack);
        const std::string label = fixed_text(v, x_digits);
        text(canvas, label, {x - text_width(label, 0.4) / 2, top + plot_h + 20}, 0.4);
    }
    text(canvas, x_label, {left + plot_w / 2 - text_width(x_label) / 2, height - 15});
    for (int t = 0; t <= 4; ++t) {
        const double p = y_max * t / 4;
        const std::array<double, 1> one = {p};
        const std::string label = fixed_text(p, decimals_for(one));
        cv::line(canvas, {left - 5, y_of(p)}, {left, y_of(p)}, kBlack);
        text(canvas, label, {left - 10 - text_width(label, 0.4), y_of(p) + 5}, 0.4);
    }
    text(canvas, "% of points", {5, top - 10}, 0.4);
    text(canvas, title, {left + 80, 25}, 0.55);
    // Legend, top right.
    int legend_y = top + 18;
    for (std::size_t s = 0; s < series.size(); ++s) {
        std::string entry = series[s].label + ": RMS " + fixed_text(rms[s], 4) + " mm, " +
                            std::to_string(counts[s]) + " values";
        if (outside[s])
            entry += ", " + std::to_string(outside[s]) + " outside";
        const int w = text_width(entry, 0.42);
        const int x = left + plot_w - w - 10;
        cv::rectangle(canvas, {x - 24, legend_y - 11}, {x - 8, legend_y + 1},
                      colours[s % colours.size()], cv::FILLED);
        text(canvas, entry, {x, legend_y}, 0.42);
        legend_y += 20;
    }
    return canvas;
}

// ------------------------------------------------------------------ timing

namespace {

// "1 s", "100 ms", "10 us" for 10^e seconds.
std::string decade_label(int e) {
    int unit_exp = 0;
    const char* unit = "s";
    if (e < -6) {
        unit_exp = -9;
        unit = "ns";
    } else if (e < -3) {
        unit_exp = -6;
        unit = "us";
    } else if (e < 0) {
        unit_exp = -3;
        unit = "ms";
    }
    int mantissa = 1;
    for (int k = unit_exp; k < e; ++k)
        mantissa *= 10;
    return std::to_string(mantissa) + " " + unit;
}

const cv::Scalar kSeriesColours[] = {
    {40, 40, 200},  // red (BGR)
    {180, 90, 30},  // blue
    {60, 150, 40},  // green
    {150, 60, 140}, // purple
    {20, 140, 220}, // orange
};

} // namespace

cv::Mat timing_plot(const std::vector<int>& sizes, const std::vector<PlotSeries>& series,
                    const std::string& title) {
    const int width = 960, height = 620;
    const int left = 100, right = 30, top = 60, bottom = 80;
    cv::Mat image(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    double lo = std::numeric_limits<double>::infinity(), hi = 0;
    for (const PlotSeries& s : series)
        for (double t : s.seconds)
            if (t > 0 && std::isfinite(t)) {
                lo = std::min(lo, t);
                hi = std::max(hi, t);
            }
    if (!(hi > 0) || sizes.empty())
        return image;
    const int e_lo = static_cast<int>(std::floor(std::log10(lo)));
    const int e_hi = std::max(e_lo + 1, static_cast<int>(std::ceil(std::log10(hi))));
    const double n_max = double(sizes.back()) * 1.05;
    const auto px = [&](double n) {
        return left + static_cast<int>(std::lround(n / n_max * double(width - left - right)));
    };
    const auto py = [&](double t) {
        const double f = (std::log10(t) - double(e_lo)) / double(e_hi - e_lo);
        return height - bottom - static_cast<int>(std::lround(f * double(height - top - bottom)));
    };
    const cv::Scalar axis(0, 0, 0), grid(220, 220, 220), text(40, 40, 40);
    const int font = cv::FONT_HERSHEY_SIMPLEX;
    for (int e = e_lo; e <= e_hi; ++e) {
        const int y = py(std::pow(10.0, double(e)));
        cv::line(image, {left, y}, {width - right, y}, grid, 1);
        cv::putText(image, decade_label(e), {8, y + 5}, font, 0.5, text, 1, cv::LINE_AA);
    }
    for (int n : sizes) {
        const int x = px(double(n));
        cv::line(image, {x, top}, {x, height - bottom}, grid, 1);
        const std::string label = std::to_string(n);
        cv::putText(image, label, {x - 4 * static_cast<int>(label.size()), height - bottom + 22},
                    font, 0.5, text, 1, cv::LINE_AA);
    }
    cv::line(image, {left, top}, {left, height - bottom}, axis, 1);
    cv::line(image, {left, height - bottom}, {width - right, height - bottom}, axis, 1);
    cv::putText(image, "window size N (N x N camera pixels)", {left + 220, height - 25}, font, 0.6,
                text, 1, cv::LINE_AA);
    cv::putText(image, title, {left, 35}, font, 0.65, text, 1, cv::LINE_AA);
    int legend_y = top + 20;
    for (const PlotSeries& s : series) {
        cv::Point previous{-1, -1};
        for (std::size_t i = 0; i < sizes.size() && i < s.seconds.size(); ++i) {
            if (!(s.seconds[i] > 0) || !std::isfinite(s.seconds[i]))
                continue;
            const cv::Point p{px(double(sizes[i])), py(s.seconds[i])};
            if (previous.x >= 0)
                cv::line(image, previous, p, s.colour, 2, cv::LINE_AA);
            cv::circle(image, p, 4, s.colour, cv::FILLED, cv::LINE_AA);
            previous = p;
        }
        cv::line(image, {left + 20, legend_y - 5}, {left + 60, legend_y - 5}, s.colour, 2,
                 cv::LINE_AA);
        cv::putText(image, s.label, {left + 70, legend_y}, font, 0.55, text, 1, cv::LINE_AA);
        legend_y += 24;
    }
    return image;
}

cv::Scalar series_colour(std::size_t i) {
    return kSeriesColours[i % (sizeof(kSeriesColours) / sizeof(kSeriesColours[0]))];
}

} // namespace fpp::calib
