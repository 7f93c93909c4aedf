#pragma once
// Trueness a user can state: what the calibration's own uncertainty means
// for the lengths a scan measures. stereo_calibrate propagates the
// covariance of the calibrated parameters (both lenses, distortion and
// correction grids, R and T; the board poses marginalised) to first order
// through triangulation (camera pixel and projector column, as the table and
// SV reconstruction measure) to the length between two points.
//
// Conventions: camera frame, mm. "Along depth": two points on the camera's
// optical axis (X = Y = 0), length_mm apart, centred at the depth; "across":
// two points on the camera's X axis direction at that depth, centred on the
// optical axis. Sigmas are one standard deviation of the measured length
// minus the true one, mm; ppm = sigma / length x 1e6. The depths are the
// session's: the 10th percentile, the median and the 90th percentile of the
// used poses' corners' Z.
//
// The frame's own place (a rigid motion of the whole cloud) cannot be
// observed and is no error here; lengths and form are what a user checks.

#include "fpp/coefficient_table.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <array>
#include <string>
#include <vector>

namespace fpp::calib {

struct LengthSigma {
    double depth_mm = 0;       // where the length is centred (camera Z)
    double along_depth_mm = 0; // 1 sigma, mm
    double across_mm = 0;      // 1 sigma, mm
};

// Stored with the calibration (calibration-file.md), the table
// (coefficient-table.md) and each scan's scan.json.
struct Trueness {
    double length_mm = 0;            // 0: unknown
    std::array<LengthSigma, 3> at{}; // the session's near, middle and far depth
    bool known() const { return length_mm > 0; }
    const LengthSigma& middle() const { return at[1]; }
    double depth_ppm() const { return known() ? at[1].along_depth_mm / length_mm * 1e6 : 0; }
    double across_ppm() const { return known() ? at[1].across_mm / length_mm * 1e6 : 0; }
};

// The predicted sigma over the camera image: per cell (cell_px square,
// row-major from the top left), 1 sigma error of a length_mm length along
// the ray of the cell's centre pixel, centred at depth_mm; NaN where the
// camera model has no ray.
struct TruenessMap {
    Image<float> sigma_mm;
    int cell_px = 0;
    double depth_mm = 0;
    double length_mm = 0;
};

// The session's depths (camera Z of the used poses' corners, mm): 10th
// percentile, median, 90th percentile.
struct SessionDepths {
    double near_mm = 0, middle_mm = 0, far_mm = 0;
};

// A board pose a session could take next and what it would do for the
// depth scale: the sigma along depth at the middle depth once the pose is
// added to the session (the pose's camera corners weighed into the
// adjustment that holds the poses, its own pose marginalised; the
// projector's share held as it is). Board frame as the session's
// (checkerboard_points): X_c = R X_b + t.
struct PoseSuggestion {
    Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Vec3 t{0, 0, 0};
    Vec2 image_point{};       // where the board's centre shows, camera px
    double depth_mm = 0;      // the board centre's camera Z
    double tilt_deg = 0;      // between the board's normal and the camera's optical axis
    std::string far_edge;     // "top", "bottom", "left", "right": the edge tilted away
    std::string image_region; // "upper left", "centre", ...
    double sigma_mm = 0;      // predicted sigma along depth with this pose added
    // "tilt the board about 35 degrees (its left edge away from the
    // camera), in the upper left of the image, at about 450 mm".
    std::string words() const;
};

// The figures a table's header holds (coefficient-table.md): the middle
// depth's; all 0 when unknown.
inline TableTrueness table_trueness(const Trueness& t) {
    if (!t.known())
        return {};
    return {float(t.length_mm), float(t.middle().depth_mm), float(t.middle().along_depth_mm),
            float(t.middle().across_mm)};
}

struct StereoCalibration;

// The length between two camera-frame points (mm) as a scanner calibrated
// with `measure` measures it when `truth` is the real rig: each point's
// camera pixel and projector column through `truth`, then triangulated
// through `measure` (where its camera ray meets the projector column). NaN
// when a point has no ray or no intersection.
double measured_length(const StereoCalibration& truth, const StereoCalibration& measure,
                       const Vec3& a, const Vec3& b);

// A few lines a person reads (reports, session checks): the sigma along
// depth and across at the middle depth, in mm per length and ppm, and at the
// near and far depths. "unknown" when !t.known().
std::string trueness_summary(const Trueness& t);

} // namespace fpp::calib
