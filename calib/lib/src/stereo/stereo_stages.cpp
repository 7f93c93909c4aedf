// The stages of stereo_calibrate's bundle adjustment (see stereo_stages.hpp).

#include "stereo/stereo_stages.hpp"

#include "trueness/calibration_covariance.hpp"
#include "trueness/session_advice.hpp"
#include "trueness/trueness_prediction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace fpp::calib::detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double square(double v) {
    return v * v;
}

// Exact simulated data would give infinite weights; no calibration is
// better than a thousandth of a pixel.
double noise_floor(double sigma) {
    return std::isfinite(sigma) ? std::max(sigma, 1e-3) : 1.0;
}

// The focal lengths times `k` with the image unchanged: the same pixel for
// the same direction scaled in depth, i.e. normalised coordinates divided
// by k, so the distortion terms of order n in them times k^(n-1), and skew
// as the focal lengths.
void scale_focal_lengths(LensModel& lens, double k) {
    lens.fu *= k;
    lens.fv *= k;
    lens.skew *= k;
    lens.k1 *= k * k;
    lens.k2 *= std::pow(k, 4);
    lens.k3 *= std::pow(k, 6);
    lens.p1 *= k;
    lens.p2 *= k;
}

struct PoseRms {
    double camera = 0, projector = 0, combined = 0;
    int points = 0;
};

PoseRms pose_rms(const std::vector<Vec2>& cam_res, const std::vector<Vec2>& proj_res) {
    PoseRms r;
    double sc = 0, sp = 0;
    int nc = 0, np = 0;
    for (const Vec2& e : cam_res)
        if (std::isfinite(e[0])) {
            sc += e[0] * e[0] + e[1] * e[1];
            ++nc;
        }
    for (const Vec2& e : proj_res)
        if (std::isfinite(e[0])) {
            sp += e[0] * e[0] + e[1] * e[1];
            ++np;
        }
    r.camera = nc ? std::sqrt(sc / nc) : 0;
    r.projector = np ? std::sqrt(sp / np) : 0;
    r.combined = (nc + np) ? std::sqrt((sc + sp) / (nc + np)) : 0;
    r.points = nc;
    return r;
}

// The middle value (the upper median); 0 for none.
double median_of(std::vector<double> values) {
    if (values.empty())
        return 0;
    const auto middle = values.begin() + std::ptrdiff_t(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    return *middle;
}

} // namespace

StereoRun::StereoRun(const std::vector<PoseObservations>& poses_, Size camera_size_,
                     Size projector_size_, const StereoOptions& options_, const StereoStart& start)
    : poses(poses_), camera_size(camera_size_), projector_size(projector_size_), options(options_),
      pool(ThreadPool::shared(options_.threads)) {
    result.skew_estimated = options.skew;
    result.initial_camera_rms = start.camera_rms;
    result.initial_projector_rms = start.projector_rms;
    s.camera = start.camera;
    s.projector = start.projector;
    s.R = start.R;
    s.T = start.T;
    s.poses = start.board_poses;
    if (!options.camera_grid.empty())
        s.camera_grid =
            CorrectionGrid(camera_size, options.camera_grid.columns, options.camera_grid.rows);
    if (!options.projector_grid.empty())
        s.projector_grid = CorrectionGrid(projector_size, options.projector_grid.columns,
                                          options.projector_grid.rows);
    initial = s;
    result.procedure = options.procedure;

    for (std::size_t i = 0; i < poses.size(); ++i)
        for (std::size_t k = 0; k < poses[i].board.size(); ++k)
            corners.push_back({static_cast<int>(i), poses[i].board[k], poses[i].camera[k],
                               poses[i].projector[k]});
    regularisation = {options.camera_grid_smoothness, options.projector_grid_smoothness,
                      options.grid_ridge};
    used.assign(poses.size(), true);
}

void StereoRun::say(const std::string& line) const {
    if (options.progress)
        options.progress(line);
}

void StereoRun::place_dense_samples() {
    dense.clear();
    dense_origin.clear();
    for (std::size_t i = 0; i < poses.size(); ++i) {
        if (!used[i])
            continue;
        const PoseObservations& o = poses[i];
        for (std::size_t k = 0; k < o.dense_camera.size(); ++k) {
            dense.push_back(
                {{}, o.dense_projector[k], 1.0, static_cast<int>(i), o.dense_camera[k]});
            dense_origin.emplace_back(static_cast<int>(i), static_cast<int>(k));
        }
    }
    std::vector<bool> placed;
    place_dense_points(s, dense, &placed);
    std::size_t kept = 0;
    for (std::size_t k = 0; k < dense.size(); ++k)
        if (placed[k]) {
            dense[kept] = dense[k];
            dense_origin[kept] = dense_origin[k];
            ++kept;
        }
    dense.resize(kept);
    dense_origin.resize(kept);
}

std::size_t StereoRun::drop_dense_outliers(double sigmas, double floor_px) {
    if (dense.empty())
        return 0;
    const StereoCalibration model = calibration_of(s);
    std::vector<double> error(dense.size());
    for (std::size_t k = 0; k < dense.size(); ++k) {
        const Vec2 up = model.projector_pixel(dense[k].camera_point);
        error[k] = std::hypot(up[0] - dense[k].projector[0], up[1] - dense[k].projector[1]);
    }
    // The median of a 2D Gaussian error's magnitude is 1.1774 sigma.
    const double limit = std::max(sigmas * median_of(error) / 1.1774, floor_px);
    std::size_t kept = 0;
    for (std::size_t k = 0; k < dense.size(); ++k)
        if (error[k] <= limit) {
            dense[kept] = dense[k];
            dense_origin[kept] = dense_origin[k];
            ++kept;
        }
    const std::size_t dropped = dense.size() - kept;
    dense.resize(kept);
    dense_origin.resize(kept);
    return dropped;
}

ObservationNoise StereoRun::observation_noise(const RigState& at) const {
    const StereoCalibration model = calibration_of(at);
    double sc = 0, sp = 0, sd = 0;
    std::size_t nc = 0, np = 0;
    for (const CornerObservation& o : corners) {
        const RigidPose& pose = at.poses[std::size_t(o.pose)];
        const Vec2 c = project_camera(model, pose, o.board);
        sc += std::pow(c[0] - o.camera[0], 2) + std::pow(c[1] - o.camera[1], 2);
        ++nc;
        if (std::isfinite(o.projector[0])) {
            const Vec2 p = project_projector(model, pose, o.board);
            sp += std::pow(p[0] - o.projector[0], 2) + std::pow(p[1] - o.projector[1], 2);
            ++np;
        }
    }
    for (const DenseObservation& o : dense) {
        const Vec2 p = model.projector_pixel(o.camera_point);
        sd += std::pow(p[0] - o.projector[0], 2) + std::pow(p[1] - o.projector[1], 2);
    }
    ObservationNoise n;
    n.camera = nc ? std::sqrt(sc / double(2 * nc)) : 1;
    n.projector = np ? std::sqrt(sp / double(2 * np)) : n.camera;
    n.dense = dense.empty() ? n.projector : std::sqrt(sd / double(2 * dense.size()));
    n.camera = noise_floor(n.camera);
    n.projector = noise_floor(n.projector);
    n.dense = noise_floor(n.dense);
    return n;
}

void StereoRun::camera_first_stages(int round) {
    say(std::string(round == 0 ? "" : "again without the outlying poses: ") +
        "the camera alone from its corners (intrinsics, skew " +
        (options.skew ? "estimated" : "fixed at 0") + ", distortion" +
        (s.camera_grid.empty() ? "" : ", correction grid") + ", board poses)");
    // Every kind of observation is weighted by 1 / its noise
    // variance (so that the grids' regularisation means the same on
    // a simulated rig with 0.005 px corners as on a real one with
    // 0.2 px): first from OpenCV's initial residuals, then from the
    // residuals of each stage.
    ObservationNoise noise;
    noise.camera = noise_floor(result.initial_camera_rms / std::sqrt(2.0));
    noise.projector = noise_floor(result.initial_projector_rms / std::sqrt(2.0));
    FreeParameters free;
    free.camera_lens = free.poses = free.camera_observations = true;
    free.camera_grid = !s.camera_grid.empty();
    free.skew = options.skew;
    free.camera_weight = 1 / square(noise.camera);
    if (free.camera_grid && options.camera_grid_smoothness == 0) {
        StageTimer validation(result.time_split, "camera grid cross-validation");
        regularisation.camera_smoothness = choose_camera_smoothness(
            s, corners, used, free, regularisation, options, pool, result.camera_grid_validation);
    }
    result.camera_grid_smoothness = regularisation.camera_smoothness;
    StageTimer camera_stage(result.time_split, "camera adjustment");
    camera_outcome = adjust(s, corners, {}, used, free, regularisation, options.max_iterations,
                            options.progress, &pool);
    camera_stage.stop();
    camera_free = free;
    if (options.camera_focal_scale != 1) {
        say("the camera's focal lengths scaled by " + std::to_string(options.camera_focal_scale) +
            " (a depth scale measured elsewhere), the boards placed again");
        scale_focal_lengths(s.camera, options.camera_focal_scale);
        FreeParameters place;
        place.poses = place.camera_observations = true;
        place.camera_weight = free.camera_weight;
        adjust(s, corners, {}, used, place, regularisation, options.max_iterations,
               options.progress, &pool);
    }
    say("the projector with the camera and the boards held, from its corners "
        "(intrinsics, distortion, R, T)");
    free = {};
    free.projector_lens = free.stereo = free.projector_observations = true;
    free.skew = options.skew;
    free.projector_weight = 1 / square(noise.projector);
    StageTimer projector_stage(result.time_split, "projector adjustment (corners)");
    projector_outcome = adjust(s, corners, {}, used, free, regularisation, options.max_iterations,
                               options.progress, &pool);
    projector_stage.stop();
    result.iterations += camera_outcome.iterations + projector_outcome.iterations;
    // Then with the dense samples and the grid. Samples off the
    // model (decoded to the wrong fringe, the board's edge against a
    // wall behind it, a speck on the board) are dropped first against
    // the corners' model, then once more against the dense one:
    // squared residuals would let a few of them bend the projector.
    StageTimer dense_stage(result.time_split, "projector adjustment (dense samples)");
    place_dense_samples();
    if (!dense.empty() || !s.projector_grid.empty()) {
        const std::size_t placed = dense.size();
        // Loose against the corners' model, which lacks the grid:
        // only samples decoded to the wrong fringe go.
        const std::size_t dropped = drop_dense_outliers(10, 5);
        say("the projector again with " + std::to_string(dense.size()) +
            " dense samples of the boards' bright parts (" + std::to_string(dropped) + " of " +
            std::to_string(placed) + " off the corners' model dropped)" +
            (s.projector_grid.empty() ? "" : " and its correction grid"));
        free.projector_grid = !s.projector_grid.empty();
        noise = observation_noise(s);
        free.projector_weight = 1 / square(noise.projector);
        free.dense_weight = 1 / square(noise.dense);
        projector_outcome = adjust(s, corners, dense, used, free, regularisation,
                                   options.max_iterations, options.progress, &pool);
        result.iterations += projector_outcome.iterations;
        // Weighted again by the residuals of the grid's model, and
        // without the samples that are still off it.
        const std::size_t again = drop_dense_outliers(5, 0.5);
        say("  again with the residuals' weights" +
            (again ? " and without " + std::to_string(again) + " dense samples off the model"
                   : std::string()));
        noise = observation_noise(s);
        free.projector_weight = 1 / square(noise.projector);
        free.dense_weight = 1 / square(noise.dense);
        projector_outcome = adjust(s, corners, dense, used, free, regularisation,
                                   options.max_iterations, options.progress, &pool);
        result.iterations += projector_outcome.iterations;
    }
    dense_stage.stop();
    projector_free = free;
}

void StereoRun::joint_stage(int round) {
    say(round == 0 ? "joint bundle adjustment (both devices, skew " +
                         std::string(options.skew ? "estimated" : "fixed at 0") + ")"
                   : "bundle adjustment again without the outlying poses");
    FreeParameters free;
    free.camera_lens = free.projector_lens = free.stereo = free.poses = true;
    free.camera_grid = !s.camera_grid.empty();
    free.projector_grid = !s.projector_grid.empty();
    free.camera_observations = free.projector_observations = true;
    free.skew = options.skew;
    // Without grids, the paper's: every residual in pixels alike.
    // With them, weighted by 1 / the noise variance as the
    // camera-first stages (the grids' regularisation is in those
    // units): from OpenCV's initial residuals, then from the joint's.
    const bool grids = free.camera_grid || free.projector_grid;
    if (grids) {
        free.camera_weight = 1 / square(noise_floor(result.initial_camera_rms / std::sqrt(2.0)));
        free.projector_weight =
            1 / square(noise_floor(result.initial_projector_rms / std::sqrt(2.0)));
    }
    // The camera grid's stiffness is the camera lens's: chosen as in
    // camera_first, from the camera's corners alone (left at 0, the
    // grid would be held by its ridge only and trade with the focal
    // lengths and the poses: 2 % of aspect ratio on 6 real poses).
    if (free.camera_grid && options.camera_grid_smoothness == 0) {
        FreeParameters camera_only;
        camera_only.camera_lens = camera_only.camera_grid = camera_only.poses = true;
        camera_only.camera_observations = true;
        camera_only.skew = options.skew;
        camera_only.camera_weight = free.camera_weight;
        StageTimer validation(result.time_split, "camera grid cross-validation");
        regularisation.camera_smoothness =
            choose_camera_smoothness(s, corners, used, camera_only, regularisation, options, pool,
                                     result.camera_grid_validation);
    }
    result.camera_grid_smoothness = regularisation.camera_smoothness;
    StageTimer joint_timer(result.time_split, "joint adjustment");
    camera_outcome = adjust(s, corners, {}, used, free, regularisation, options.max_iterations,
                            options.progress, &pool);
    if (grids) {
        const ObservationNoise noise = observation_noise(s);
        free.camera_weight = 1 / square(noise.camera);
        free.projector_weight = 1 / square(noise.projector);
        camera_outcome = adjust(s, corners, {}, used, free, regularisation, options.max_iterations,
                                options.progress, &pool);
    }
    projector_outcome = camera_outcome;
    result.iterations += camera_outcome.iterations;
    camera_free = projector_free = free;
}

void StereoRun::residuals() {
    // Per-pose residuals and outliers among the used poses.
    StageTimer residuals_stage(result.time_split, "residuals");
    StereoCalibration& c = result.calibration;
    c = calibration_of(s, camera_size, projector_size);
    result.camera_residuals.assign(poses.size(), {});
    result.projector_residuals.assign(poses.size(), {});
    std::vector<double> combined;
    std::vector<PoseRms> rms(poses.size());
    for (std::size_t i = 0; i < poses.size(); ++i) {
        const PoseObservations& o = poses[i];
        for (std::size_t k = 0; k < o.board.size(); ++k) {
            const Vec2 uc = project_camera(c, s.poses[i], o.board[k]);
            result.camera_residuals[i].push_back({uc[0] - o.camera[k][0], uc[1] - o.camera[k][1]});
            if (std::isfinite(o.projector[k][0]) && std::isfinite(o.projector[k][1])) {
                const Vec2 up = project_projector(c, s.poses[i], o.board[k]);
                result.projector_residuals[i].push_back(
                    {up[0] - o.projector[k][0], up[1] - o.projector[k][1]});
            } else {
                result.projector_residuals[i].push_back({kNaN, kNaN});
            }
        }
        rms[i] = pose_rms(result.camera_residuals[i], result.projector_residuals[i]);
        if (used[i])
            combined.push_back(rms[i].combined);
    }
    result.dense_residuals.assign(poses.size(), {});
    for (std::size_t i = 0; i < poses.size(); ++i)
        result.dense_residuals[i].assign(poses[i].dense_camera.size(), {kNaN, kNaN});
    double dense_sum = 0;
    place_dense_points(s, dense);
    for (std::size_t k = 0; k < dense.size(); ++k) {
        const Vec2 up = c.projector_pixel(dense[k].camera_point);
        const Vec2 e{up[0] - dense[k].projector[0], up[1] - dense[k].projector[1]};
        result.dense_residuals[std::size_t(dense_origin[k].first)]
                              [std::size_t(dense_origin[k].second)] = e;
        dense_sum += e[0] * e[0] + e[1] * e[1];
    }
    result.dense_rms = dense.empty() ? -1 : std::sqrt(dense_sum / double(dense.size()));
    const double median = median_of(combined);
    result.outliers.clear();
    for (std::size_t i = 0; i < poses.size(); ++i)
        if (used[i] && rms[i].combined > options.outlier_factor * median)
            result.outliers.push_back(static_cast<int>(i));

    c.poses.clear();
    double sc = 0, sp = 0;
    int nc = 0, np = 0;
    for (std::size_t i = 0; i < poses.size(); ++i) {
        PoseResidual pr;
        pr.name = poses[i].name;
        pr.camera_rms = rms[i].camera;
        pr.projector_rms = rms[i].projector;
        pr.corners = rms[i].points;
        pr.used = used[i];
        if (!used[i])
            pr.note = "dropped as an outlier";
        const bool outlier = std::find(result.outliers.begin(), result.outliers.end(),
                                       static_cast<int>(i)) != result.outliers.end();
        if (outlier) {
            std::ostringstream msg;
            msg.precision(3);
            msg << "outlier: RMS " << rms[i].combined << " px > " << options.outlier_factor
                << " x median " << median << " px";
            pr.note = msg.str();
        }
        c.poses.push_back(pr);
        if (!used[i])
            continue;
        for (const Vec2& e : result.camera_residuals[i]) {
            sc += e[0] * e[0] + e[1] * e[1];
            ++nc;
        }
        for (const Vec2& e : result.projector_residuals[i])
            if (std::isfinite(e[0])) {
                sp += e[0] * e[0] + e[1] * e[1];
                ++np;
            }
    }
    c.camera_rms = nc ? std::sqrt(sc / nc) : -1;
    c.projector_rms = np ? std::sqrt(sp / np) : -1;

    // Uncertainties: covariance = (J^T J)^-1 * residual variance, per stage.
    result.camera_sigma = LensModel{};
    result.projector_sigma = LensModel{};
    const auto sigmas = [&](const AdjustmentOutcome& o, int device, LensModel& out) {
        const int dof = o.residuals - o.parameters;
        if (dof <= 0)
            return;
        const double variance = o.data_cost / dof;
        double sg[kLensParameters];
        for (int k = 0; k < kLensParameters; ++k)
            sg[k] =
                std::sqrt(o.lens_variance[std::size_t(device * kLensParameters + k)] * variance);
        out = LensModel{sg[0], sg[1], sg[2], sg[3], sg[4], sg[5], sg[6], sg[9], sg[7], sg[8]};
    };
    sigmas(camera_outcome, 0, result.camera_sigma);
    sigmas(projector_outcome, 1, result.projector_sigma);
    combined_rms = std::move(combined);
}

bool StereoRun::leave_outliers_out() {
    if (!options.drop_outliers || result.outliers.empty())
        return false;
    const int remaining = static_cast<int>(combined_rms.size() - result.outliers.size());
    if (remaining < 3) {
        say("not dropping the outliers: fewer than 3 poses would remain");
        return false;
    }
    for (int i : result.outliers)
        used[static_cast<std::size_t>(i)] = false;
    s = initial; // again from the start, without the outlying poses
    return true;
}

// The board poses, and the calibration's covariance carried to the lengths
// a user measures (trueness.hpp): into the calibration and the result's map. A covariance that
// cannot be formed leaves the trueness unknown, with the reason in the progress.
StereoResult StereoRun::finish() {
    result.board_poses = s.poses;
    const bool camera_first = options.procedure == StereoProcedure::camera_first;

    StageTimer stage(result.time_split, "trueness (the calibration's covariance)");
    say("the calibration's uncertainty carried to lengths (trueness)");
    try {
        const CalibrationCovariance covariance =
            camera_first ? camera_first_covariance(s, corners, dense, used, camera_free,
                                                   projector_free, regularisation, &pool)
                         : joint_covariance(s, corners, used, camera_free, regularisation, &pool);
        TruenessInputs in;
        in.state = &s;
        in.covariance = &covariance.sigma;
        in.camera_size = result.calibration.camera_size;
        in.depths = session_depths(s, corners, used);
        Eigen::VectorXd gradient;
        in.middle_depth_gradient = &gradient;
        const Trueness t = predict_trueness(in, &result.trueness_map);
        bool finite = true;
        for (const LengthSigma& at : t.at)
            finite = finite && std::isfinite(at.along_depth_mm) && std::isfinite(at.across_mm);
        if (finite && options.suggest_next_poses > 0) {
            AdviceInputs advice;
            advice.state = &s;
            advice.covariance = &covariance;
            advice.gradient = &gradient;
            advice.camera_size = result.calibration.camera_size;
            advice.projector_size = result.calibration.projector_size;
            advice.board = poses.front().board;
            advice.depths = board_centre_depths(s, advice.board, used);
            advice.count = options.suggest_next_poses;
            result.next_poses = suggest_poses(advice).next;
        }
        if (finite)
            result.calibration.trueness = t;
        else
            say("trueness unknown: the covariance is not finite (a parameter the session does "
                "not determine)");
    } catch (const std::runtime_error& e) {
        say(std::string("trueness unknown: ") + e.what());
    }
    stage.stop(); // into the result, before it is handed on
    return std::move(result);
}

} // namespace fpp::calib::detail
