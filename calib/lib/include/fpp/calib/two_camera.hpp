#pragma once
// Two-camera scanning: two cameras each decode the projector coordinate of
// the same fringe capture; points come from matching the two decoded maps
// along rectified rows and triangulating camera to camera, so the projector
// needs no calibration (it is only a texture).
//
// Frames and conventions:
// - Camera 1's frame is the world frame, mm; X_2 = R X_1 + T
//   (CameraPairCalibration). Pixel centres on integers in every image.
// - Rectification: the rotations R1, R2 of OpenCV's stereoRectify (X_r1 =
//   R1 X_1, X_r2 = R2 X_2 = X_r1 - (b, 0, 0)), and one rectified pinhole shared
//   by both cameras: focal f (the mean of the four focal lengths, so that a
//   rectified pixel is about a camera pixel), principal point (cx, cy) placed
//   so that the second camera's whole image lands on a grid of integer
//   rectified pixels. Pixels are mapped with fpp::LensModel's own functions
//   (its full distortion model), never with OpenCV's undistortion.
// - Camera 1 is not resampled: each of its pixels keeps its decoded
//   coordinate u1 and gets its exact rectified position (x1, y1). Camera 2's
//   decoded u2 (and v2) are resampled onto the rectified grid (bilinear, only
//   between four valid neighbours within max_step_px of each other).
// - Matching, per camera-1 pixel, on rectified rows floor(y1) and floor(y1)+1
//   of camera 2: a crossing is a pair of neighbouring valid columns (x, x+1)
//   whose u2 brackets u1, rising in the direction u rises in most of the
//   image (so non-monotone pairs are rejected) and changing by at most
//   max_step_px (so gaps and depth edges are never bridged); the sub-pixel x'
//   is linear between them. Several crossings on a row: with v decoded in
//   both cameras the one whose v2 is nearest v1 (within max_v_px), else they
//   must lie within cluster_px of each other (one surface, noise) and are
//   averaged, or the pixel is ambiguous. The two rows' x' must exist and
//   differ by at most max_row_step_px; x' is interpolated at y1.
// - Occlusion: a camera-1 pixel whose surface camera 2 cannot see still finds
//   its u on camera 2's row, on the nearer surface that hides it (same
//   projector column, other point). Camera 2 sees, along each ray, the
//   nearest point, i.e. the largest |disparity|: each match marks camera 2's
//   rectified cells it lands on (the 2 x 2 around (x', y1)) with its
//   |disparity|, and a match whose cells hold one larger by more than
//   occlusion_margin_px is dropped.
// - Triangulation by rectified disparity d = x1 - x': Z_r = f b / d, and the
//   point on camera 1's own ray through the pixel (X_1 = R1^T Z_r (x1 - cx,
//   y1 - cy, f) / f). Camera 1's ray carries no matching error, and on
//   rectified rows the two rays are coplanar, so this is the exact
//   intersection (the midpoint of the rays would equal it, at more cost).

#include "fpp/calib/camera_pair.hpp"
#include "fpp/decoder.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"
#include "fpp/point_cloud.hpp"

#include <cstddef>
#include <string>

namespace fpp::calib {

struct TwoCameraOptions {
    double max_step_px = 6.0;     // projector px between neighbouring samples of one surface
    double max_v_px = 2.0;        // |v2 - v1| allowed when both cameras decode y, projector px
    double cluster_px = 1.5;      // crossings this close (rectified px) are one surface
    double max_row_step_px = 3.0; // |x'(row) - x'(row + 1)|, rectified px
    // A pixel whose camera-2 cells hold a disparity larger than its own by
    // more than this (rectified px) is hidden from camera 2.
    double occlusion_margin_px = 2.0;
    int threads = 0; // 0 = all cores
    // Throws std::invalid_argument naming the field for a value out of range.
    void validate() const;
};

struct TwoCameraRectification {
    Mat3 R1{1, 0, 0, 0, 1, 0, 0, 0, 1}; // X_r1 = R1 X_1
    Mat3 R2{1, 0, 0, 0, 1, 0, 0, 0, 1}; // X_r2 = R2 X_2
    double f = 1, cx = 0, cy = 0;       // shared rectified pinhole, px
    double baseline = 0;                // b: X_r2 = X_r1 - (b, 0, 0), mm
    Size grid;                          // camera 2's rectified grid
};

struct TwoCameraStats {
    std::size_t first_valid = 0;  // camera-1 pixels with a decoded u
    std::size_t second_valid = 0; // camera-2 pixels with a decoded u
    std::size_t points = 0;
    std::size_t outside = 0;      // rectified row outside camera 2's image
    std::size_t no_match = 0;     // u1 not found on a row (occluded, out of view, gap)
    std::size_t ambiguous = 0;    // several surfaces on the row, no v to choose
    std::size_t v_disagree = 0;   // v2 differs from v1 at every crossing
    std::size_t row_mismatch = 0; // the two rows' matches disagree
    std::size_t behind = 0;       // disparity of the wrong sign (behind the cameras)
    std::size_t occluded = 0;     // hidden from camera 2 by a nearer matched surface
    double coverage() const {     // points / first_valid
        return first_valid ? double(points) / double(first_valid) : 0.0;
    }
};

class TwoCameraReconstructor {
public:
    // Throws std::invalid_argument if the calibration has no sizes, a lens
    // cannot be inverted, or the cameras are not side by side (the baseline
    // must lie mostly along x: rows are the epipolar lines).
    explicit TwoCameraReconstructor(const CameraPairCalibration& pair,
                                    const TwoCameraOptions& options = {});

    // Matches and triangulates. `first` and `second` are decodes of the same
    // pattern sequence by camera 1 and camera 2 (sizes as the calibration);
    // proj_x is required, proj_y used when both have it. The cloud is
    // organised on camera 1's pixels (camera 1's frame, mm; NaN where no
    // point), quality and intensity from `first`. Throws
    // std::invalid_argument on sizes that differ from the calibration's.
    TwoCameraStats reconstruct(const DecodeResult& first, const DecodeResult& second,
                               PointCloud& cloud) const;

    const TwoCameraRectification& rectification() const { return rect_; }

private:
    CameraPairCalibration pair_;
    TwoCameraOptions options_;
    TwoCameraRectification rect_;
    Image<float> first_rectified_; // 2 channels per camera-1 pixel: (x1, y1), NaN if none
    Image<float> second_source_;   // 2 channels per rectified cell: camera-2 pixel, NaN if none
};

} // namespace fpp::calib
