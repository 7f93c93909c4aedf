#pragma once
// The depth scale a certified length shows (`fpp-calib correct`): a ball
// bar measured in several positions, each giving the vector between its
// sphere centres d = (d_x, d_y, d_z) (camera frame, mm). A scanner whose
// depth is scaled by s measures the bar's depth component s times too long;
// the correction k (multiply measured depths by k) makes the lengths
// |(d_x, d_y, k d_z)| match the certificate. It is the smallest model the
// lengths support: one number, seen only by positions that reach in depth
// (a length across the image does not change with k).
//
// Fit: least squares of the length residuals over the positions, Gauss-
// Newton from k = 1 (linearised, SD_i ~ -(k - 1) d_z^2 / |d|). Its sigma
// combines the residuals' scatter (per position, n - 1 degrees of freedom)
// and the certificate's uncertainty, which is the same for every position
// and so does not average out.
//
// Refusals (InputError, "refused as inconsistent, never corrected" where the
// data contradict each other), checked by check_depth_scale_fit:
//   - fewer than 2 positions, or fewer than 2 reaching in depth;
//   - a position whose residual after the fit is beyond
//     max_position_residual_mm (a capture or the certificate is wrong);
//   - a correction beyond max_sigmas of what the calibration's predicted
//     trueness and the certificate's uncertainty allow.

#include "fpp/calib/trueness.hpp"
#include "fpp/lens_model.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace fpp::calib {

struct DepthScaleOptions {
    // A position reaches in depth when |d_z| / |d| is at least this (the
    // VDI positions tilted in depth: 0.5; across the image: 0).
    double min_depth_share = 0.25;
    int min_depth_positions = 2;
    double max_position_residual_mm = 0.03;
    double max_sigmas = 5;
    // The limit when the calibration has no predicted trueness (ppm of a
    // length along depth, 1 sigma).
    double unknown_trueness_ppm = 1000;
};

// One position of the bar: where it was measured and its centre vector.
struct LengthObservation {
    std::filesystem::path capture; // named in errors
    Vec3 vector{};                 // second centre minus first, camera frame, mm
};

struct DepthScaleFit {
    double scale = 1;                // k: multiply measured depth by it
    double sigma = 0;                // 1 sigma of k
    double scatter_mm = 0;           // RMS residual length after the fit (n - 1 dof)
    std::vector<double> residual_mm; // per position, length after the fit - certified
    std::vector<double> depth_share; // per position, |d_z| / |d|
    std::vector<double> before_mm;   // per position, measured length - certified (SD)
    int depth_positions = 0;         // positions reaching in depth
    double correction_ppm() const { return (scale - 1) * 1e6; }
};

// Throws InputError("command line", "CAPTURE", why) for fewer than 2
// positions or fewer than min_depth_positions reaching in depth, naming
// each position's depth share. Does not judge the fit (check_depth_scale_fit).
DepthScaleFit fit_depth_scale(const std::vector<LengthObservation>& positions, double certified_mm,
                              double certificate_sigma_mm, const DepthScaleOptions& options = {});

// The largest |k - 1| the calibration allows: max_sigmas x (the predicted
// trueness along depth, as a share of its length, plus the certificate's
// uncertainty over its length).
double depth_scale_limit(const Trueness& predicted, double certified_mm,
                         double certificate_sigma_mm, const DepthScaleOptions& options = {});

// The refusals above; `artefact` and `calibration` are the files named.
void check_depth_scale_fit(const DepthScaleFit& fit,
                           const std::vector<LengthObservation>& positions,
                           const Trueness& predicted, double certified_mm,
                           double certificate_sigma_mm, const std::filesystem::path& artefact,
                           const std::filesystem::path& calibration,
                           const DepthScaleOptions& options = {});

// The corrected calibration's trueness: along depth from the fit (k's sigma
// times each length, the same share at every depth), across as predicted.
Trueness trueness_from_fit(const Trueness& predicted, const DepthScaleFit& fit,
                           double certified_mm);

// "k - 1 = +812 ppm +- 35 ppm (4 positions, 4 reaching in depth, scatter
// 0.003 mm)".
std::string depth_scale_text(const DepthScaleFit& fit);

} // namespace fpp::calib
