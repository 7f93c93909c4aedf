#pragma once
// Evaluation of reconstructions (camera frame, mm):
//   - figures in the style of VDI/VDE 2634 part 2 from shape fits: flatness
//     (range of the signed distances to the least-squares plane, also after
//     excluding the 0.3 % of points farthest from it, as the guideline
//     allows), probing error form P_F (range of the sphere fit's radial
//     residuals) and size P_S (fitted minus calibrated diameter), sphere
//     spacing error SD (measured minus calibrated centre distance), and the
//     cylinder's form and diameter;
//   - errors against a simulated capture's ground truth, per camera pixel;
//   - distances between two reconstructions of the same camera, per pixel
//     (organised clouds) or to the nearest point (any clouds).
//
// Per-pixel comparisons: the point and the reference at one camera pixel lie
// on the same camera ray, so their difference is along it; it is reported as
// the signed Z difference (point minus reference) and the 3D distance.

#include "fpp/calib/shape_fit.hpp"
#include "fpp/image.hpp"
#include "fpp/point_cloud.hpp"

#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace fpp::calib {

// The valid points of a cloud and, when organised, each point's camera pixel.
struct CloudPoints {
    std::vector<Vec3> points;          // mm, camera frame, all finite
    std::vector<std::uint32_t> pixels; // row * organised.width + column; empty if unorganised
    Size organised;                    // camera image size; {0, 0} if unorganised
    bool is_organised() const { return organised.area() > 0; }
};

// From a PLY file's vertices (`origin` is the file named in errors). Vertices
// with a non-finite coordinate are dropped. The cloud is organised when the
// file records the organised size (obj_info) and a pixel index per vertex;
// a pixel index outside that size, or one used twice, throws InputError.
CloudPoints cloud_points(const PlyPoints& ply, const std::filesystem::path& origin);
// From an organised cloud: its slots with finite X, Y and Z.
CloudPoints cloud_points(const PointCloud& cloud);

// Statistics of signed values (errors) or distances; all 0 when empty.
struct ErrorStats {
    std::size_t count = 0;
    double mean = 0, rms = 0, stddev = 0, min = 0, max = 0, max_abs = 0;
};
ErrorStats error_stats(std::span<const double> values);

// Per-point values of an organised cloud as a 1-channel image of its
// organised size, NaN where there is no point.
// Throws std::invalid_argument if the cloud is not organised or the sizes differ.
Image<float> values_image(const CloudPoints& cloud, std::span<const double> values);

// ---------------------------------------------------------------- VDI/VDE 2634-2

// Share of points the guideline allows to exclude before taking a range.
inline constexpr double kGuidelineExcludedFraction = 0.003;

// Residual range after excluding floor(fraction * used) used points with the
// largest |residual| and refitting on the rest.
struct TrimmedRange {
    double range = 0;
    double rms = 0;
    std::size_t excluded = 0;
};

struct FlatnessFigures {
    PlaneFit fit;         // least-squares plane over the points (inliers if robust)
    double flatness = 0;  // max - min signed distance to it
    TrimmedRange trimmed; // the same after the guideline's exclusion (plane refitted)
};
FlatnessFigures flatness_figures(std::span<const Vec3> points, const FitOptions& options = {},
                                 double excluded_fraction = kGuidelineExcludedFraction);

struct ProbingFigures {
    SphereFit fit;
    double form = 0;                  // P_F: max - min radial residual
    TrimmedRange form_trimmed;        // after the guideline's exclusion (sphere refitted)
    double diameter = 0;              // fitted
    std::optional<double> size_error; // P_S: fitted - nominal diameter
};
ProbingFigures probing_figures(std::span<const Vec3> points, std::optional<double> nominal_diameter,
                               const FitOptions& options = {},
                               double excluded_fraction = kGuidelineExcludedFraction);

struct CylinderFigures {
    CylinderFit fit;
    double form = 0; // max - min radial residual
    double diameter = 0;
    std::optional<double> diameter_error; // fitted - nominal
};
CylinderFigures cylinder_figures(std::span<const Vec3> points,
                                 std::optional<double> nominal_diameter,
                                 const FitOptions& options = {});

struct BallBarFigures {
    BallBarFit fit;
    std::vector<std::uint8_t> cluster;   // sphere (0 = first, 1 = second) of every point
    double length = 0;                   // measured centre distance
    std::optional<double> spacing_error; // SD: measured - nominal centre distance
    double form_first = 0, form_second = 0;
    std::optional<double> size_error_first, size_error_second; // fitted - nominal diameter
};
// One cloud holding both spheres (fit_ball_bar's clustering).
BallBarFigures ball_bar_figures(std::span<const Vec3> points, std::optional<double> nominal_length,
                                std::optional<double> nominal_diameter,
                                const FitOptions& options = {});

// ---------------------------------------------------------------- ground truth

struct TruthComparison {
    ErrorStats dz; // Z(point) - Z(truth), mm
    // dz less its least-squares a + b X + c Y (X, Y true, camera frame): the
    // error's shape once a depth offset and a tilt, the pose errors a
    // calibration leaves, are taken out. mm.
    ErrorStats dz_shape;
    ErrorStats distance; // |point - truth|, mm
    // The one rigid motion of the whole cloud that brings it closest to the
    // truth (least squares over every compared point; no scale): the place
    // of a calibration's camera frame cannot be observed, so the truth error
    // a user can hold a scanner to is the one left after it. X_truth ~ R X + t.
    Mat3 rigid_rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Vec3 rigid_translation{};   // mm
    double rigid_angle_rad = 0; // rigid_rotation's angle
    ErrorStats distance_rigid;  // |R point + t - truth|, mm (nothing if < 3 compared)
    std::vector<double> distance_rigid_values; // per compared point, as dz_values
    std::size_t truth_pixels = 0;              // pixels with a true surface
    std::size_t compared = 0;                  // pixels with both a point and a true surface
    std::size_t no_surface = 0;                // points at pixels where the truth has no surface
    double coverage = 0;                       // compared / truth_pixels
    std::vector<double> dz_values;             // per compared point, in the cloud's point order
    Image<float> dz_map;                       // Z difference per pixel, NaN where not compared
};
// `truth_xyz`: 3-channel float image of the cloud's organised size (camera
// frame, mm, NaN = no surface). Throws std::invalid_argument otherwise, or
// if the cloud is not organised.
TruthComparison compare_with_truth(const CloudPoints& cloud, const Image<float>& truth_xyz);

// ---------------------------------------------------------------- cloud to cloud

struct CloudDistance {
    bool per_pixel = false;
    ErrorStats distance;     // 3D distance from each point of the first cloud to its match
    ErrorStats dz;           // per pixel only: Z(first) - Z(second)
    std::size_t matched = 0; // points of the first cloud with a match
    std::size_t only_first =
        0; // per pixel: points of the first cloud alone; nearest: beyond max distance
    std::size_t only_second = 0; // per pixel: points of the second cloud alone
    std::vector<double> values;  // per match: Z difference (per pixel) or distance (nearest)
    Image<float> dz_map;         // per pixel only: Z difference, NaN where not both
};
// Same camera pixel in both clouds. Throws std::invalid_argument unless both
// are organised with the same size.
CloudDistance compare_per_pixel(const CloudPoints& first, const CloudPoints& second);
// Each point of `first` to the nearest point of `second` (k-d tree); points
// further than max_distance count as unmatched. Throws std::invalid_argument
// if `second` is empty.
CloudDistance compare_nearest(const CloudPoints& first, const CloudPoints& second,
                              double max_distance = std::numeric_limits<double>::infinity());

// ---------------------------------------------------------------- figures table

struct Figure {
    std::string name; // dotted, e.g. "cloud.plane.flatness"
    double value = 0;
    std::string unit; // "mm", "deg", "%", "" for counts
};
// "name,value,unit" header and one row per figure; values with 9 significant digits.
std::string figures_csv(const std::vector<Figure>& figures);

} // namespace fpp::calib
