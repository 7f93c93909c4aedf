#pragma once
// A verification figure's values against its maximum permissible error
// (fpp-calib verify): one marker per value in the order measured, the band
// the MPE allows shaded, values outside it drawn red. 8-bit BGR, ASCII text
// (as fpp/calib/plots.hpp).

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace fpp::calib {

// `labels`: one per value (e.g. "1", "2/1"), under the markers. A signed
// figure (SD, P_S) gets the band -mpe .. +mpe, an unsigned one (P_F, F)
// 0 .. mpe; without an MPE no band. Lengths in mm.
cv::Mat mpe_plot(const std::vector<double>& values, const std::vector<std::string>& labels,
                 std::optional<double> mpe, bool signed_figure, const std::string& x_label,
                 const std::string& y_label, const std::string& title);

} // namespace fpp::calib
