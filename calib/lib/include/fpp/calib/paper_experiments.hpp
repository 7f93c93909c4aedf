#pragma once
// The paper's experiments reproduced on the virtual scanner, in one run, with
// every calibration procedure measured against the truth.
//
// Setup: by default the paper rig with effects and a projector lens defect
// outside every stereo model (board/sim/paper-rig-lens-defects.yaml: gamma,
// defocus, noise, prism and trefoil distortion, sized so that SV's plane-fit
// RMS is the paper's 0.118 mm); any rig file with --rig; optionally the
// camera binned.
//
// Procedures and the methods they give (a method turns a decoded scan into
// points):
//   reference  `exact`: SV with the rig's own model, defects and all: what the
//              scan's noise and decoding leave, no calibration error
//   paper      the paper's: a joint stereo calibration without correction
//              grids from `checkerboard_poses` poses (or, with
//              SvCalibrationSource::rig_model, the rig's 5-coefficient
//              model): `sv-paper`; flat boards (`plane_poses`, gray-x) placed
//              by that SV: `paper-polynomial`, `paper-ray`, `paper-rational`
//   boards     ours (the tools' default): one checkerboard session of
//              `board_poses` poses (gray-xy) gives the camera-first stereo
//              calibration with correction grids (`sv`) and the hybrid
//              tables, boards placed by the camera (`boards-<model>`, the
//              rational one the default; `boards-only-rational` and
//              `model-only-rational` fitted to one kind of sample)
//   planes     our calibration with the paper's flat boards
//              (`planes-rational`)
//
// Scans (gray-x, saved as capture sets with ground truth), each reconstructed
// by every method:
//   plane     Experiment 1: a 230 x 175 mm board tilted by ~20 deg at 480 mm;
//             plane-fit RMS, histograms, signed residual maps
//   cylinder  Experiment 2: 168 mm diameter, 215 mm long, axis vertical, front
//             at 500 mm; cylinder-fit RMS and diameter
//   sphere    ours: 120 mm diameter at 520 mm; sphere-fit RMS and diameter
//   ball bars ours: two 25 mm spheres 200 mm apart at seven places and
//             directions in the volume; the sphere-spacing error (VDI/VDE
//             2634-2) and the spheres' size errors
//   relief    Experiment 3: the face relief scaled so that about 680,000
//             camera pixels (at full size; / binning^2) see it; RMS distance
//             between the paper's SV and its hybrid clouds per pixel,
//             reconstruction times with one thread each (best of `timing_runs`)
//   windows   Experiment 4: N x N windows of the plane scan (N = 100 .. 800 at
//             full size, / binning): the paper's SV on the cropped camera
//             (principal point shifted) and our tables cropped, one thread each
// Every scan is also rendered noise-free (read noise 0, no shot noise), and
// both versions are compared with the ground truth pixel by pixel (Z
// difference along the camera ray, and 3D distance), nothing removed first;
// the shape error (less its own offset and tilt) is reported beside it.
// Shape fits and truth errors use, per scan, the pixels where every method
// gives a point, so that no method is judged on an easier subset.
//
// Reconstruction time is phase -> XYZ only (decoding is common to both).
//
// Output folder (written as a whole: a temporary sibling renamed at the end):
//   calib.yaml, calib-paper.yaml   our and the paper's stereo calibrations
//   stereo-report/, stereo-report-paper/   their reports
//   table-<method>.fpt          one coefficient table per table method
//   hybrid-report-<method>/     its hybrid calibration report
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
    int checkerboard_poses = 15; // the paper's 15 (its stereo calibration)
    int plane_poses = 30;        // the paper's 30 (its flat boards)
    int board_poses = 30;        // our checkerboard session
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
    std::vector<std::string> methods; // every method's key, e.g. "sv-paper", "boards-rational"
    std::string default_method;       // the tools' default procedure and model
    std::vector<Figure> figures;      // as in report/figures.csv
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
// window is not inside the camera, or the camera has a correction grid.
StereoCalibration crop_calibration(const StereoCalibration& calibration, int x0, int y0, Size size);
// The table of the same camera window (same tiling, model, axis, projector,
// hash); every coefficient copied with get/set. Throws std::invalid_argument
// if the window is not inside the table's camera.
CoefficientTable crop_table(const CoefficientTable& table, int x0, int y0, Size size);
// The decoded images (proj_x, proj_y, modulation, mean, mask) of the window.
DecodeResult crop_decode(const DecodeResult& decoded, int x0, int y0, Size size);

} // namespace fpp::calib
