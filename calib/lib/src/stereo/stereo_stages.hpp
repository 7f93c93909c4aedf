#pragma once
// The stages of stereo_calibrate's bundle adjustment (internal), named as
// the procedure runs them (stereo_calibrate.hpp says what each procedure
// is; stereo_calibrate() runs them, round by round):
//   camera_first_stages  the camera alone from its corners (its grid's
//                        smoothness by cross-validation), then the projector
//                        with the camera and the boards held, from its
//                        corners, then with the dense samples and its grid
//   joint_stage          both devices, R, T and the boards together
//   residuals            per-pose RMS, outlying poses, the lenses' sigmas
//   finish               the board poses, the trueness from the covariance
//                        (calibration_covariance.hpp) and the pose advice
// Every kind of observation is weighted by 1 / its noise variance, from
// OpenCV's initial residuals, then from the residuals of each stage.

#include "fpp/calib/stereo_calibrate.hpp"
#include "fpp/parallel.hpp"
#include "stereo/bundle_adjustment.hpp"

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace fpp::calib::detail {

// The camera grid's smoothness by K-fold cross-validation over the poses
// (StereoOptions::camera_grid_smoothness): each fold's poses placed by a
// camera calibrated without them; each choice's held-out RMS is appended to
// `validation` (grid_smoothness.cpp).
double choose_camera_smoothness(const RigState& from, const std::vector<CornerObservation>& corners,
                                const std::vector<bool>& used_poses, const FreeParameters& free,
                                const GridRegularisation& reg, const StereoOptions& options,
                                ThreadPool& pool,
                                std::vector<std::pair<double, double>>& validation);

// RMS per coordinate of each kind of observation (px).
struct ObservationNoise {
    double camera = 1, projector = 1, dense = 1;
};

// One calibration's state between its stages.
struct StereoRun {
    StereoRun(const std::vector<PoseObservations>& poses, Size camera_size, Size projector_size,
              const StereoOptions& options, const StereoStart& start);

    void camera_first_stages(int round);
    void joint_stage(int round);
    void residuals();
    // The outlying poses left out for a second round from the start; false
    // when none are, or fewer than 3 poses would remain.
    bool leave_outliers_out();
    StereoResult finish();

    const std::vector<PoseObservations>& poses;
    Size camera_size, projector_size;
    const StereoOptions& options;
    ThreadPool& pool;
    StereoResult result;
    RigState s, initial;
    std::vector<CornerObservation> corners;
    GridRegularisation regularisation;
    // The dense samples of the used poses, placed on their boards by the
    // camera (its rays meet the boards' planes), and each one's (pose, index).
    std::vector<DenseObservation> dense;
    std::vector<std::pair<int, int>> dense_origin;
    std::vector<bool> used;
    AdjustmentOutcome camera_outcome, projector_outcome;
    // What the last adjustments held free, with their weights: the
    // covariance is theirs.
    FreeParameters camera_free, projector_free;
    std::vector<double> combined_rms; // of the used poses, by residuals()

private:
    void say(const std::string& line) const;
    void place_dense_samples();
    // Drops the dense samples further from the projector model than
    // max(sigmas x the robust sigma, floor_px); returns how many.
    std::size_t drop_dense_outliers(double sigmas, double floor_px);
    ObservationNoise observation_noise(const RigState& at) const;
};

} // namespace fpp::calib::detail
