#pragma once
// Internal to fpp-calib paper-experiments (paper_experiments.hpp): what a run
// measures, shared by the run itself (paper_stages.hpp: paper_experiments.cpp,
// paper_scans.cpp, paper_timing.cpp) and its report and targets
// (paper_report.cpp).

#include "fpp/calib/evaluation.hpp"
#include "fpp/calib/frame_turn.hpp"
#include "fpp/calib/paper_experiments.hpp"
#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/simulator/rig.hpp"

#include <cstddef>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace fpp::calib::paper {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The paper's figures (Vargas et al., experiments 1 to 3).
inline constexpr double kPaperPlaneSv = 0.118, kPaperPlaneHybrid = 0.044;       // mm, plane-fit RMS
inline constexpr double kPaperCylinderSv = 0.076, kPaperCylinderHybrid = 0.059; // mm
inline constexpr double kPaperReliefDistance = 0.075;                           // mm, SV vs hybrid
inline constexpr double kPaperReliefSvSeconds = 1.04, kPaperReliefHybridSeconds = 0.14;
inline constexpr double kPaperReliefPoints = 683047;

// Scenes (camera frame, mm).
inline constexpr double kPlaneWidth = 230, kPlaneHeight = 175, kPlaneDistance = 480;
inline constexpr double kPlaneTiltXDeg = 4, kPlaneTiltYDeg = -20; // ~20 deg to the optical axis
inline constexpr double kCylinderDiameter = 168, kCylinderLength = 215, kCylinderFront = 500;
inline constexpr double kSphereDiameter = 120, kSphereCentreZ = 520;
inline constexpr double kBallDiameter = 25, kBallBarLength = 200; // VDI/VDE 2634-2 ball bar
inline constexpr double kReliefPixelsFullSize = 680000; // camera pixels seeing it at 1600 x 1200
inline constexpr double kReliefBaseZ = 530;             // its base; heights rise towards the camera
inline constexpr double kReliefWidth = 160, kReliefHeight = 220; // Relief::face_bumps() at scale 1
inline constexpr int kWindowSizes = 8;
inline constexpr int kWindowStepFullSize = 100; // N = 100, 200, ..., 800 at full size

// Pixels this close to the edge of the reconstructed region are left out of
// fits and truth comparisons: at a silhouette a pixel's phase is blurred with
// its neighbours' (defocus) and its point is off the surface.
inline constexpr int kEdgeMarginPx = 2;

// Targets.
inline constexpr double kPlaneRatioTarget = 0.5; // paper: hybrid truth error <= half of SV's
inline constexpr double kSpeedupTarget = 50;     // hybrid at least this much faster on the relief
inline constexpr double kTruthRmsNoisy = 0.03, kTruthRmsNoiseFree = 0.015;  // mm
inline constexpr double kTruthBias = 0.01;                                  // mm
inline constexpr double kDiameterError = 0.01, kBallBarSpacingError = 0.02; // mm
inline constexpr double kCalibrationSeconds = 20; // 30 full-size poses, stereo and hybrid

// How a method was calibrated.
enum class Procedure {
    reference, // the rig's exact model (no calibration): what the scan itself leaves
    paper,     // the paper's: joint stereo calibration, flat boards placed by SV
    planes,    // our stereo calibration, flat boards placed by SV
    boards,    // ours: one checkerboard session, boards placed by the camera (the default)
};
const char* procedure_title(Procedure p);

// One way of turning a decoded scan into points.
struct Method {
    std::string key;   // figures.csv, file names: "sv-paper", "paper-rational", ...
    std::string title; // the report
    Procedure procedure = Procedure::boards;
    bool is_default = false;
    // Whether its points decide the pixels every method is compared on
    // (false for a variant that covers less of the image: it is compared on
    // those pixels where it has a point).
    bool in_common = true;
    std::unique_ptr<SvReconstructor> sv;            // SV methods
    const StereoCalibration* calibration = nullptr; // SV methods
    CoefficientTable table;                         // table methods
    TableModel model = TableModel::rational;
    // Table methods: its hybrid calibration.
    int usable_poses = 0, poses = 0;
    std::size_t pixels_modelled = 0;
    double fit_rms_z_median = kNaN, sigma_z_median = kNaN;
    double seconds = 0;
    bool is_table() const { return !table.empty(); }
};

enum class FitKind { plane, cylinder, sphere, none };

// One scan, every method.
struct ScanSummary {
    std::string key;   // figures.csv name part
    std::string title; // summary.md
    FitKind fit = FitKind::none;
    double nominal_diameter = 0;
    std::size_t truth_pixels = 0;
    std::size_t common = 0;
    std::vector<std::size_t> points;                       // per method
    std::vector<double> fit_rms, diameter, diameter_error; // per method (NaN: no fit), noisy scan
    std::vector<double> fit_rms_clean, diameter_clean;     // the same on the noise-free scan
    std::string fit_note;
    std::vector<ErrorStats> truth_noisy, truth_clean; // per method, Z error
    std::vector<ErrorStats> shape_noisy, shape_clean; // per method: bias and tilt removed
    std::vector<ErrorStats> distance_clean;           // per method: 3D distance to the truth
    // Per method, noise-free: the Z error with the points turned by their
    // calibration's camera frame turn (Record::paper_turn, our_turn), i.e.
    // in the true frame's orientation; beside truth_clean, never instead.
    std::vector<ErrorStats> turned_clean;
    std::size_t compared_noisy = 0, compared_clean = 0;
};

// A ball bar at one place and direction in the volume.
struct BallBarPosition {
    Vec3 centre{}, axis{};
    std::vector<double> spacing_error, spacing_error_clean; // per method, mm (NaN: no fit)
    std::vector<double> size_error;                         // per method: worse sphere, noisy
};

struct ReliefSummary {
    double scale = 1;
    std::size_t pixels_seen = 0;
    // Per table method of the paper's procedure: SV (the paper's) against it.
    std::vector<std::size_t> compared_methods;
    std::vector<double> distance_rms, dz_rms;
    std::vector<std::size_t> matched;
    std::vector<double> seconds;              // per method, one thread (NaN: not timed)
    double seconds_sv_plane_iteration = kNaN; // the paper's SV iteration
};

struct WindowSummary {
    std::vector<int> sizes;
    std::vector<std::size_t> methods;         // the methods timed
    std::vector<std::size_t> points;          // SV points per window
    std::vector<std::vector<double>> seconds; // [timed method][window]
    double crop_max_difference_mm = 0;        // cropped vs full-image reconstruction
    std::size_t crop_mismatched = 0;          // pixels with a point in one only
};

struct StereoSummary {
    bool calibrated = false; // false: the rig's 5-coefficient model (paper, rig-model)
    std::string procedure;
    int poses = 0;
    double camera_rms = kNaN, projector_rms = kNaN, dense_rms = kNaN;
    double camera_grid_max = 0, projector_grid_max = 0, camera_grid_smoothness = 0;
    double seconds = 0;
    std::string origin;
};

// Everything a run measured, for the report and the targets.
struct Record {
    PaperExperimentOptions options;
    sim::Rig rig;
    std::vector<Method> methods;
    StereoSummary paper_stereo, our_stereo;
    // Each calibration's camera frame against the rig's, from the camera's
    // rays alone (frame_turn.hpp): what no board data can observe.
    FrameTurn paper_turn, our_turn;
    const FrameTurn* turn_of(Procedure p) const; // null for the reference
    double seconds_boards_hybrid = 0;            // our table's hybrid calibration (all its models)
    std::vector<ScanSummary> scans;
    std::vector<BallBarPosition> ball_bars;
    ReliefSummary relief;
    WindowSummary windows;
    double seconds_sessions = 0;

    std::size_t find(const std::string& key) const; // methods.size() if absent
    const ScanSummary* scan(const std::string& key) const;
    std::size_t default_method() const;
};

// The run's targets (the paper's relations for its procedure, and the
// absolute ones for the default method), each met or not.
std::vector<PaperTarget> evaluate_targets(const Record& record);
// report/summary.md.
std::string summary_markdown(const Record& record, const std::vector<PaperTarget>& targets);
// "1.234 s", "12.34 ms", "56.7 us", "-".
std::string seconds_text(double s);

} // namespace fpp::calib::paper
