#pragma once
// The paper's experiments reproduced on the virtual scanner, in one run.
//
// Setup: by default the paper rig with effects and a projector lens defect
// outside every stereo model (board/sim/paper-rig-lens-defects.yaml: gamma,
// defocus, noise, prism and trefoil distortion, sized so that SV's plane-fit
// RMS is the paper's 0.118 mm), optionally with the camera binned. A checkerboard session (gray-xy)
// gives the stereo (SV) calibration (or, with SvCalibrationSource::rig_model, the rig's own
// 5-coefficient model); a flat-board session (gray-x, vertical fringes only, as the paper) gives
// one hybrid coefficient table per table model.
//
// Scans (gray-x, saved as capture sets with ground truth), each reconstructed
// by SV with the projector column only (the paper's SV) and by every table:
//   plane     Experiment 1: a 230 x 175 mm board tilted by ~20 deg at 480 mm;
//             plane-fit RMS, histograms, signed residual maps
//   cylinder  Experiment 2: 168 mm diameter, 215 mm long, axis vertical, front
//             at 500 mm; cylinder-fit RMS and diameter
//   sphere    ours: 120 mm diameter at 520 mm; sphere-fit RMS and diameter
//   relief    Experiment 3: the face relief scaled so that about 680,000
//             camera pixels (at full size; / binning^2) see it; RMS distance
//             between the SV and the hybrid clouds per pixel, reconstruction
//             times with one thread each (best of `timing_runs`)
//   windows   Experiment 4: N x N windows of the plane scan (N = 100 .. 800 at
//             full size, / binning): the SV reconstructor of the cropped camera
//             (principal point shifted) and the kernel on the cropped table,
//             one thread each
// Every scan is also rendered noise-free (read noise 0, no shot noise), and
// both versions are compared with the ground truth pixel by pixel (Z
// difference along the camera ray): the noise-free errors isolate each
// model's own error. Shape fits and truth errors use, per scan, the pixels
// where SV and every table give a point, so that no model is judged on an
// easier subset.
//
// Reconstruction time is phase -> XYZ only (decoding is common to both).
//
// Output folder (written as a whole: a temporary sibling renamed at the end):
//   calib.yaml                 stereo calibration (fpp-stereo/1)
//   stereo-report/             its report
//   table-<model>.fpt          one coefficient table per model
//   hybrid-report-<model>/     hybrid calibration report per model
//   scans/<scan>/              the noisy scans as capture sets with truth
//   sessions/                  the calibration sessions (only with keep_sessions)
//   report/summary.md          the paper's numbers beside ours, tables, targets
//   report/figures.csv         name,value,unit
//   report/*.png               histograms, signed maps, the window timing plot

#include "fpp/calib/evaluation.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/decoder.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace fpp::calib {

// Where the SV model comes from.
enum class SvCalibrationSource {
    // A stereo calibration from a simulated checkerboard session (the paper's
    // procedure). Its fitted 5-coefficient lenses absorb much of the rig's
    // distortion outside that model.
    checkerboard,
    // The rig's own lenses and pose restricted to the 5-coefficient model
    // (k4 and the prism terms dropped): a perfect calibration that cannot
    // represent that distortion at all, i.e. SV with a known model deficit,
    // as the paper's real lenses gave its SV. No checkerboard session.
    rig_model,
};
// "checkerboard", "rig-model"; parse throws std::invalid_argument otherwise.
const char* to_string(SvCalibrationSource source);
SvCalibrationSource parse_sv_calibration_source(const std::string& name);

struct PaperExperimentOptions {
    SvCalibrationSource sv_calibration = SvCalibrationSource::checkerboard;
    int binning = 1;             // camera binning (1 = the paper's 1600 x 1200)
    std::uint64_t seed = 1;      // poses, noise
    int checkerboard_poses = 15; // the paper's 15
    int plane_poses = 30;        // the paper's 30
    int timing_runs = 3;         // best of this many runs per timing
    int threads = 0;             // simulation, decoding, calibration (timings use 1); 0 = all
    bool keep_sessions = false;  // keep the calibration sessions in the output
    std::filesystem::path rig;   // empty: paper-rig-lens-defects.yaml
    std::function<void(const std::string&)> progress;

    // Throws std::invalid_argument naming the first bad field.
    void validate() const;
};

// One target of the run (met or not; never adjusted to pass).
struct PaperTarget {
    std::string key;         // figures.csv name after "target."
    std::string description; // one line
    bool met = false;
    std::string detail; // the numbers compared
};

struct PaperExperimentResult {
    std::vector<std::string> models; // table models run, e.g. "polynomial", "ray"
    std::string default_model;       // HybridOptions{}.model
    std::vector<Figure> figures;     // as in report/figures.csv
    std::vector<PaperTarget> targets;
    std::string summary_markdown; // report/summary.md
    double seconds = 0;
};

// Runs everything into `out`, which must not exist and whose parent must
// exist (InputError otherwise, before anything is done). Throws
// std::invalid_argument for bad options, IoError for OS failures; a failure
// leaves nothing behind.
PaperExperimentResult run_paper_experiments(const std::filesystem::path& out,
                                            const PaperExperimentOptions& options);

// Every table model, the paper's (polynomial) first.
std::vector<TableModel> available_table_models();

// The calibration of the camera window [x0, x0 + size.width) x [y0, y0 +
// size.height): same lenses and extrinsics, principal point shifted by
// (-x0, -y0), camera size `size`. Pixel (u, v) of the window is pixel
// (u + x0, v + y0) of the full camera. Throws std::invalid_argument if the
// window is not inside the camera.
StereoCalibration crop_calibration(const StereoCalibration& calibration, int x0, int y0, Size size);
// The table of the same camera window (same tiling, model, axis, projector,
// hash); every coefficient copied with get/set. Throws std::invalid_argument
// if the window is not inside the table's camera.
CoefficientTable crop_table(const CoefficientTable& table, int x0, int y0, Size size);
// The decoded images (proj_x, proj_y, modulation, mean, mask) of the window.
DecodeResult crop_decode(const DecodeResult& decoded, int x0, int y0, Size size);

} // namespace fpp::calib
