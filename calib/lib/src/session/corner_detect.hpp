#pragma once
// The detector stage of find_checkerboard (internal): OpenCV's finders on a
// reduced copy of a texture whose shading has been divided out, giving the
// board's corners as starting points only: cornerSubPix and the corner model
// on the full texture end where they did from the earlier detector's (within
// 1e-3 px on 157 of 162 simulated poses tilted up to 45 degrees; on 4 closer
// to the truth, on 1 without its 14 px outlier; SLStudio's real boards give
// the same calibration to every printed digit).

#include "fpp/image.hpp"

#include <opencv2/core.hpp>

#include <vector>

namespace fpp::calib::detail {

enum class Finder {
    classic, // cv::findChessboardCorners: its histogram and global thresholds only
    sector,  // cv::findChessboardCornersSB, default search
};

// Every finder looks at the texture reduced by this factor, so that its
// longest side is at most kDetectorSide px.
constexpr int kDetectorSide = 1000;
int detector_factor(Size texture);

// The 8-bit image the finders look at: `texture` cropped to a multiple of
// `factor`, area-averaged down by it (a block holding NaN reads 0), and
// divided by its local white level (the dilation of a window an eighth of
// the image's smaller side wide, smoothed), which is floored at a quarter of
// the image's bright level so that unlit parts stay dark (empty for a
// texture under `factor` px a side). A tilted board under a projector is lit
// unevenly across its squares; divided out, one threshold separates them
// everywhere.
cv::Mat detector_image(const Image<float>& texture, int factor);

// One finder run on `image8` (from detector_image with `factor`). On success
// `found` holds the columns x rows corners (OpenCV's order) in pixels of the
// texture itself (pixel centres on integers at both scales). Each run's work
// is bounded by the reduced image: the classic finder tries the histogram's
// binarisation and one global threshold (8 dilations each), never adaptive
// thresholds; the sector-based one its default search, no exhaustive search
// and no upsampling (the refinements at full size replace its accuracy).
bool run_finder(const cv::Mat& image8, int factor, int columns, int rows, Finder finder,
                std::vector<cv::Point2f>& found);

} // namespace fpp::calib::detail
