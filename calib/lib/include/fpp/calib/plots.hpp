#pragma once
// PNG figures of the host tool's reports (OpenCV drawing, 8-bit BGR, Hershey
// fonts so ASCII text only).
//
//   map_figure          a scalar per pixel or per cell in false colour with a
//                       labelled colour bar (no value black; coarse maps
//                       enlarged)
//   signed_map_figure   a signed scalar per camera pixel on a diverging
//                       blue-white-red colour map with symmetric limits and a
//                       labelled colour bar (pixels without a value grey)
//   histogram_figure    one or more histograms overlaid in distinct colours
//                       (percent of each series per bin), with a legend
//   timing_plot         times against a size on a log axis, one line per series
//
// Report folders and the PNG writer are in fpp/calib/report_folder.hpp.

#include "fpp/image.hpp"

#include <opencv2/core.hpp>

#include <span>
#include <string>
#include <vector>

namespace fpp::calib {

// printf("%.*f"), or "-" for a non-finite value.
std::string fixed_text(double value, int digits);

// The smallest 1, 2 or 5 times a power of ten that is >= value (> 0).
double nice_ceil(double value);

// Symmetric colour / histogram limit for signed values: the `quantile` of
// |value| over the finite values rounded up by nice_ceil (robust against a
// few spikes); `fallback` when there is no non-zero finite value.
double symmetric_limit(std::span<const double> values, double quantile = 0.99,
                       double fallback = 0.001);

// Diverging colour map (ColorBrewer RdBu, reversed): t = -1 dark blue, 0
// near white, +1 dark red; clamped. BGR.
cv::Vec3b diverging_colour(double t);

// Values (1-channel float image, NaN = no value) in false colour from lo to
// hi, a title, and a colour bar on the right. A map of a few cells per side
// is enlarged by whole pixels to about 400 px wide.
cv::Mat map_figure(const Image<float>& values, float lo, float hi, const std::string& title);

// Signed values per camera pixel (1-channel float image, NaN = no value)
// with colour limits +-limit, a title, and a colour bar labelled in `unit`.
// Small images are enlarged (nearest) and large ones reduced to about
// 1000 px wide.
cv::Mat signed_map_figure(const Image<float>& values, double limit, const std::string& title,
                          const std::string& unit = "mm");

struct HistogramSeries {
    std::string label;
    std::span<const double> values;
};
// Histograms of every series over [lo, hi] (80 bins; values outside are
// counted in the legend), in percent of the series' values per bin, overlaid
// in distinct colours. The legend gives label, RMS (in mm: the reports plot
// lengths) and count per series.
cv::Mat histogram_figure(const std::vector<HistogramSeries>& series, double lo, double hi,
                         const std::string& x_label, const std::string& title);

struct PlotSeries {
    std::string label;
    std::vector<double> seconds; // one per size; non-positive: no point
    cv::Scalar colour;
};
// Reconstruction time against window size N (N x N camera pixels), log time
// axis (the methods differ by orders of magnitude), one line and marker per
// series, with a legend.
cv::Mat timing_plot(const std::vector<int>& sizes, const std::vector<PlotSeries>& series,
                    const std::string& title);
// A distinct colour per series index (BGR), cycling.
cv::Scalar series_colour(std::size_t i);

} // namespace fpp::calib
