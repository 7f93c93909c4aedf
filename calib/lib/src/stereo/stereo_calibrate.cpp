// Stereo calibration: OpenCV initialisation, then the bundle adjustment of
// the chosen procedure (camera first, or joint).

#include "fpp/calib/stereo_calibrate.hpp"

#include "bundle_adjustment.hpp"
#include "trueness/calibration_covariance.hpp"
#include "trueness/session_advice.hpp"
#include "trueness/trueness_prediction.hpp"

#include "fpp/parallel.hpp"

#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <future>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace fpp::calib {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Vec3 add(const Vec3& a, const Vec3& b) {
    return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}

bool projector_valid(const PoseObservations& o, std::size_t k) {
    return std::isfinite(o.projector[k][0]) && std::isfinite(o.projector[k][1]);
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

Mat3 from_cv_rotation(const cv::Mat& rvec_or_matrix) {
    cv::Mat R;
    if (rvec_or_matrix.total() == 3)
        cv::Rodrigues(rvec_or_matrix, R);
    else
        rvec_or_matrix.convertTo(R, CV_64F);
    Mat3 out{};
    for (int k = 0; k < 9; ++k)
        out[static_cast<std::size_t>(k)] = R.at<double>(k / 3, k % 3);
    return out;
}

Vec3 from_cv_vec(const cv::Mat& v) {
    cv::Mat d;
    v.convertTo(d, CV_64F);
    return {d.at<double>(0), d.at<double>(1), d.at<double>(2)};
}

LensModel lens_from_cv(const cv::Mat& K, const cv::Mat& D) {
    LensModel l;
    l.fu = K.at<double>(0, 0);
    l.fv = K.at<double>(1, 1);
    l.cu = K.at<double>(0, 2);
    l.cv = K.at<double>(1, 2);
    l.skew = K.at<double>(0, 1);
    cv::Mat d;
    D.convertTo(d, CV_64F);
    const auto at = [&](int k) { return static_cast<int>(d.total()) > k ? d.at<double>(k) : 0.0; };
    l.k1 = at(0);
    l.k2 = at(1);
    l.p1 = at(2);
    l.p2 = at(3);
    l.k3 = at(4);
    return l;
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

} // namespace

Mat3 rotation_from_vector(const Vec3& w) {
    const double angle = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (angle < 1e-300)
        return {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const Eigen::Matrix3d m =
        Eigen::AngleAxisd(angle, Eigen::Vector3d(w[0] / angle, w[1] / angle, w[2] / angle))
            .toRotationMatrix();
    Mat3 out{};
    for (int k = 0; k < 9; ++k)
        out[static_cast<std::size_t>(k)] = m(k / 3, k % 3);
    return out;
}

Vec3 rotation_to_vector(const Mat3& R) {
    Eigen::Matrix3d m;
    for (int k = 0; k < 9; ++k)
        m(k / 3, k % 3) = R[static_cast<std::size_t>(k)];
    const Eigen::AngleAxisd aa(m);
    const Eigen::Vector3d w = aa.axis() * aa.angle();
    return {w.x(), w.y(), w.z()};
}

const char* to_string(StereoProcedure procedure) {
    return procedure == StereoProcedure::joint ? "joint" : "camera-first";
}

StereoProcedure parse_stereo_procedure(const std::string& name) {
    if (name == "camera-first")
        return StereoProcedure::camera_first;
    if (name == "joint")
        return StereoProcedure::joint;
    throw std::invalid_argument("unknown stereo procedure '" + name + "' (camera-first, joint)");
}

void StereoOptions::validate() const {
    const auto bad = [](const std::string& field, const std::string& why) {
        throw std::invalid_argument("stereo option " + field + ": " + why);
    };
    for (const auto& [grid, name] :
         {std::pair{camera_grid, "camera_grid"}, std::pair{projector_grid, "projector_grid"}})
        if (!grid.empty() &&
            (grid.columns < 4 || grid.rows < 4 || grid.columns > 64 || grid.rows > 64))
            bad(name, "a correction grid has 4 to 64 control points per axis (0 x 0: none)");
    if (!(camera_grid_smoothness >= 0) || !std::isfinite(camera_grid_smoothness))
        bad("camera_grid_smoothness", "must not be negative (0: chosen by cross-validation)");
    if (camera_grid_smoothness == 0 && camera_grid_smoothness_choices.empty())
        bad("camera_grid_smoothness_choices", "empty while camera_grid_smoothness is 0");
    for (const double c : camera_grid_smoothness_choices)
        if (!(c > 0) || !std::isfinite(c))
            bad("camera_grid_smoothness_choices", "must all be positive");
    if (camera_grid_softer_steps < 0 || camera_grid_softer_steps > 10)
        bad("camera_grid_softer_steps", "must be 0 to 10");
    if (!(projector_grid_smoothness > 0) || !std::isfinite(projector_grid_smoothness))
        bad("projector_grid_smoothness", "must be positive");
    if (!(grid_ridge > 0) || !std::isfinite(grid_ridge))
        bad("grid_ridge", "must be positive");
    if (!(outlier_factor > 1))
        bad("outlier_factor", "must be above 1");
    if (max_iterations < 1)
        bad("max_iterations", "must be at least 1");
    if (threads < 0)
        bad("threads", "must not be negative (0: all cores)");
    if (!(camera_focal_scale > 0.9 && camera_focal_scale < 1.1))
        bad("camera_focal_scale", "must be within 10 % of 1");
    if (camera_focal_scale != 1 && procedure != StereoProcedure::camera_first)
        bad("camera_focal_scale", "needs the camera-first procedure");
    if (suggest_next_poses < 0 || suggest_next_poses > 100)
        bad("suggest_next_poses", "must be 0 to 100");
}

Vec2 project_camera(const StereoCalibration& c, const RigidPose& pose, const Vec3& board) {
    return c.camera_pixel(add(mul(pose.R, board), pose.t));
}

Vec2 project_projector(const StereoCalibration& c, const RigidPose& pose, const Vec3& board) {
    return c.projector_pixel(add(mul(pose.R, board), pose.t));
}

namespace {

// Throws std::invalid_argument for what no calibration can start from.
void check_observations(const std::vector<PoseObservations>& poses) {
    if (poses.size() < 3)
        throw std::invalid_argument("stereo calibration needs at least 3 poses, got " +
                                    std::to_string(poses.size()));
    for (const PoseObservations& p : poses) {
        if (p.board.size() != p.camera.size() || p.board.size() != p.projector.size() ||
            p.dense_camera.size() != p.dense_projector.size())
            throw std::invalid_argument("pose " + p.name + ": point counts differ");
        int both = 0;
        for (std::size_t k = 0; k < p.board.size(); ++k)
            both += projector_valid(p, k) ? 1 : 0;
        if (both < 4)
            throw std::invalid_argument("pose " + p.name +
                                        ": fewer than 4 corners seen by both devices");
    }
}

// The camera grid's smoothness by K-fold cross-validation over the poses
// (StereoOptions::camera_grid_smoothness): each fold's poses placed by a
// camera calibrated without them; each choice's held-out RMS is appended to
// `validation`.
double choose_camera_smoothness(const detail::RigState& from,
                                const std::vector<detail::CornerObservation>& corners,
                                const std::vector<bool>& used_poses,
                                const detail::FreeParameters& free,
                                const detail::GridRegularisation& reg, const StereoOptions& options,
                                ThreadPool& pool,
                                std::vector<std::pair<double, double>>& validation) {
    const auto say = [&](const std::string& line) {
        if (options.progress)
            options.progress(line);
    };
    const std::vector<double>& choices = options.camera_grid_smoothness_choices;
    std::vector<int> in_use;
    for (std::size_t i = 0; i < used_poses.size(); ++i)
        if (used_poses[i])
            in_use.push_back(static_cast<int>(i));
    if (in_use.size() < 6 || choices.size() == 1) {
        validation.clear();
        return choices.front();
    }
    const int folds = std::min<int>(5, static_cast<int>(in_use.size()) / 2);
    say("choosing the camera grid's smoothness: " + std::to_string(folds) +
        "-fold cross-validation over " + std::to_string(in_use.size()) + " poses");
    detail::FreeParameters place;
    place.poses = place.camera_observations = true;
    place.camera_weight = free.camera_weight;
    // The held-out corners' RMS of each smoothness in `batch`: each
    // choice's folds are independent calibrations, all of them on the
    // pool's threads, summed in order afterwards.
    std::vector<double> tried, rms;
    const auto validate = [&](const std::vector<double>& batch) {
        const int trials = static_cast<int>(batch.size()) * folds;
        std::vector<detail::AdjustmentOutcome> held(static_cast<std::size_t>(trials));
        pool.parallel_for(trials, 1, [&](int begin, int end, int) {
            for (int t = begin; t < end; ++t) {
                const int f = t % folds;
                detail::GridRegularisation fold_reg = reg;
                fold_reg.camera_smoothness = batch[std::size_t(t / folds)];
                std::vector<bool> train = used_poses, test(used_poses.size(), false);
                for (std::size_t k = 0; k < in_use.size(); ++k)
                    if (int(k) % folds == f) {
                        train[std::size_t(in_use[k])] = false;
                        test[std::size_t(in_use[k])] = true;
                    }
                detail::RigState trial = from;
                detail::adjust(trial, corners, {}, train, free, fold_reg, options.max_iterations,
                               nullptr, &pool);
                held[std::size_t(t)] = detail::adjust(trial, corners, {}, test, place, fold_reg,
                                                      options.max_iterations, nullptr, &pool);
            }
        });
        for (std::size_t c = 0; c < batch.size(); ++c) {
            double sum = 0;
            int rows = 0;
            for (int f = 0; f < folds; ++f) {
                const detail::AdjustmentOutcome& h = held[c * std::size_t(folds) + std::size_t(f)];
                sum += h.data_cost / place.camera_weight;
                rows += h.residuals;
            }
            tried.push_back(batch[c]);
            rms.push_back(std::sqrt(sum / std::max(rows, 1)));
            validation.emplace_back(batch[c], rms.back());
            std::ostringstream msg;
            msg.precision(4);
            msg << "  smoothness " << batch[c] << ": held-out poses' corners " << rms.back()
                << " px RMS per coordinate";
            say(msg.str());
        }
    };
    const auto best_choice = [&] {
        std::size_t best = 0;
        for (std::size_t k = 1; k < rms.size(); ++k)
            if (rms[k] < 0.98 * rms[best])
                best = k;
        return best;
    };
    validate(choices);
    // While the softest choice is still the best, ten times softer: a
    // lens whose defect the grid cannot follow at the listed choices
    // (a trefoil measured: 0.105, 0.061, 0.020 px from 1e4 to 100).
    for (int extra = 0;
         extra < options.camera_grid_softer_steps && best_choice() == tried.size() - 1; ++extra)
        validate({tried.back() / 10});
    return tried[best_choice()];
}

// The calibration's covariance (calibration_covariance.hpp) carried to the
// lengths a user measures (trueness.hpp): into the calibration and the
// result's map. A covariance that cannot be formed leaves the trueness
// unknown, with the reason in the progress.
void predict_from_covariance(StereoResult& result, const detail::RigState& s,
                             const std::vector<detail::CornerObservation>& corners,
                             const std::vector<detail::DenseObservation>& dense,
                             const std::vector<bool>& used,
                             const detail::FreeParameters& camera_free,
                             const detail::FreeParameters& projector_free,
                             const detail::GridRegularisation& regularisation, bool camera_first,
                             const std::vector<PoseObservations>& poses,
                             const StereoOptions& options, ThreadPool& pool,
                             const std::function<void(const std::string&)>& say) {
    StageTimer stage(result.time_split, "trueness (the calibration's covariance)");
    say("the calibration's uncertainty carried to lengths (trueness)");
    try {
        const detail::CalibrationCovariance covariance =
            camera_first
                ? detail::camera_first_covariance(s, corners, dense, used, camera_free,
                                                  projector_free, regularisation, &pool)
                : detail::joint_covariance(s, corners, used, camera_free, regularisation, &pool);
        detail::TruenessInputs in;
        in.state = &s;
        in.covariance = &covariance.sigma;
        in.camera_size = result.calibration.camera_size;
        in.depths = detail::session_depths(s, corners, used);
        Eigen::VectorXd gradient;
        in.middle_depth_gradient = &gradient;
        const Trueness t = detail::predict_trueness(in, &result.trueness_map);
        bool finite = true;
        for (const LengthSigma& at : t.at)
            finite = finite && std::isfinite(at.along_depth_mm) && std::isfinite(at.across_mm);
        if (finite && options.suggest_next_poses > 0) {
            detail::AdviceInputs advice;
            advice.state = &s;
            advice.covariance = &covariance;
            advice.gradient = &gradient;
            advice.camera_size = result.calibration.camera_size;
            advice.projector_size = result.calibration.projector_size;
            advice.board = poses.front().board;
            advice.depths = detail::board_centre_depths(s, advice.board, used);
            advice.count = options.suggest_next_poses;
            result.next_poses = detail::suggest_poses(advice).next;
        }
        if (finite)
            result.calibration.trueness = t;
        else
            say("trueness unknown: the covariance is not finite (a parameter the session does "
                "not determine)");
    } catch (const std::runtime_error& e) {
        say(std::string("trueness unknown: ") + e.what());
    }
}

} // namespace

StereoStart initialise_stereo(const std::vector<PoseObservations>& poses, Size camera_size,
                              Size projector_size,
                              const std::function<void(const std::string&)>& progress) {
    const auto say = [&](const std::string& s) {
        if (progress)
            progress(s);
    };
    check_observations(poses);
    std::vector<std::vector<cv::Point3f>> obj_c, obj_s;
    std::vector<std::vector<cv::Point2f>> img_c, img_cs, img_ps;
    for (const PoseObservations& p : poses) {
        obj_c.emplace_back();
        img_c.emplace_back();
        obj_s.emplace_back();
        img_cs.emplace_back();
        img_ps.emplace_back();
        for (std::size_t k = 0; k < p.board.size(); ++k) {
            const cv::Point3f b(static_cast<float>(p.board[k][0]),
                                static_cast<float>(p.board[k][1]),
                                static_cast<float>(p.board[k][2]));
            const cv::Point2f c(static_cast<float>(p.camera[k][0]),
                                static_cast<float>(p.camera[k][1]));
            obj_c.back().push_back(b);
            img_c.back().push_back(c);
            if (projector_valid(p, k)) {
                obj_s.back().push_back(b);
                img_cs.back().push_back(c);
                img_ps.back().emplace_back(static_cast<float>(p.projector[k][0]),
                                           static_cast<float>(p.projector[k][1]));
            }
        }
    }
    StereoStart start;
    cv::Mat Kc, Dc, Kp, Dp, Rs, Ts, E, F;
    std::vector<cv::Mat> rvecs, tvecs, rvecs_p, tvecs_p;
    // Only a start for the bundle adjustment: from 30 iterations it reaches
    // the same result as from 200 (to 1e-8 px, measured on 30 full-size
    // poses) at half the time.
    const cv::TermCriteria criteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30,
                                    DBL_EPSILON);
    try {
        // The two devices apart from each other, at once.
        say("initialising the camera and the projector (OpenCV calibrateCamera)");
        std::future<double> camera_rms = std::async(std::launch::async, [&] {
            return cv::calibrateCamera(obj_c, img_c,
                                       cv::Size(camera_size.width, camera_size.height), Kc, Dc,
                                       rvecs, tvecs, 0, criteria);
        });
        start.projector_rms = cv::calibrateCamera(
            obj_s, img_ps, cv::Size(projector_size.width, projector_size.height), Kp, Dp, rvecs_p,
            tvecs_p, 0, criteria);
        start.camera_rms = camera_rms.get();
        say("initialising camera-to-projector transform (OpenCV stereoCalibrate)");
        cv::stereoCalibrate(obj_s, img_cs, img_ps, Kc, Dc, Kp, Dp,
                            cv::Size(camera_size.width, camera_size.height), Rs, Ts, E, F,
                            cv::CALIB_FIX_INTRINSIC, criteria);
    } catch (const cv::Exception& e) {
        throw std::runtime_error(std::string("OpenCV initialisation failed: ") + e.what());
    }
    {
        std::ostringstream msg;
        msg.precision(4);
        msg << "  OpenCV initial RMS: camera " << start.camera_rms << " px, projector "
            << start.projector_rms << " px";
        say(msg.str());
    }
    start.camera = lens_from_cv(Kc, Dc);
    start.projector = lens_from_cv(Kp, Dp);
    start.R = from_cv_rotation(Rs);
    start.T = from_cv_vec(Ts);
    for (std::size_t i = 0; i < poses.size(); ++i)
        start.board_poses.push_back({from_cv_rotation(rvecs[i]), from_cv_vec(tvecs[i])});
    return start;
}

StereoResult stereo_calibrate(const std::vector<PoseObservations>& poses, Size camera_size,
                              Size projector_size, const StereoOptions& options) {
    options.validate();
    check_observations(poses);
    TimeSplit initialisation;
    StageTimer timer(initialisation, "OpenCV initialisation");
    const StereoStart start =
        initialise_stereo(poses, camera_size, projector_size, options.progress);
    timer.stop();
    StereoResult result = stereo_calibrate(poses, camera_size, projector_size, options, start);
    initialisation.add(result.time_split);
    result.time_split = std::move(initialisation);
    return result;
}

StereoResult stereo_calibrate(const std::vector<PoseObservations>& poses, Size camera_size,
                              Size projector_size, const StereoOptions& options,
                              const StereoStart& start) {
    const auto say = [&](const std::string& s) {
        if (options.progress)
            options.progress(s);
    };
    options.validate();
    check_observations(poses);
    if (start.board_poses.size() != poses.size())
        throw std::invalid_argument("stereo calibration: the start has " +
                                    std::to_string(start.board_poses.size()) + " board poses for " +
                                    std::to_string(poses.size()) + " poses");
    StereoResult result;
    result.skew_estimated = options.skew;
    result.initial_camera_rms = start.camera_rms;
    result.initial_projector_rms = start.projector_rms;
    ThreadPool& pool = ThreadPool::shared(options.threads);

    detail::RigState s;
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
    const detail::RigState initial = s;
    result.procedure = options.procedure;

    std::vector<detail::CornerObservation> corners;
    for (std::size_t i = 0; i < poses.size(); ++i)
        for (std::size_t k = 0; k < poses[i].board.size(); ++k)
            corners.push_back({static_cast<int>(i), poses[i].board[k], poses[i].camera[k],
                               poses[i].projector[k]});
    detail::GridRegularisation regularisation{
        options.camera_grid_smoothness, options.projector_grid_smoothness, options.grid_ridge};
    const bool camera_first = options.procedure == StereoProcedure::camera_first;

    // The dense samples of the used poses, placed on their boards by the
    // camera (its rays meet the boards' planes). Per sample: pose, index.
    std::vector<detail::DenseObservation> dense;
    std::vector<std::pair<int, int>> dense_origin;
    const auto place_dense_samples = [&](const std::vector<bool>& used) {
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
        detail::place_dense_points(s, dense, &placed);
        std::size_t kept = 0;
        for (std::size_t k = 0; k < dense.size(); ++k)
            if (placed[k]) {
                dense[kept] = dense[k];
                dense_origin[kept] = dense_origin[k];
                ++kept;
            }
        dense.resize(kept);
        dense_origin.resize(kept);
    };

    // Drops the dense samples further from the projector model than
    // max(sigmas x the robust sigma, floor_px); returns how many.
    const auto drop_dense_outliers = [&](double sigmas, double floor_px) -> std::size_t {
        if (dense.empty())
            return 0;
        StereoCalibration model;
        model.projector = s.projector;
        model.projector_correction = s.projector_grid;
        model.R = s.R;
        model.T = s.T;
        std::vector<double> error(dense.size());
        for (std::size_t k = 0; k < dense.size(); ++k) {
            const Vec2 up = model.projector_pixel(dense[k].camera_point);
            error[k] = std::hypot(up[0] - dense[k].projector[0], up[1] - dense[k].projector[1]);
        }
        std::vector<double> sorted = error;
        std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(sorted.size() / 2),
                         sorted.end());
        // The median of a 2D Gaussian error's magnitude is 1.1774 sigma.
        const double limit = std::max(sigmas * sorted[sorted.size() / 2] / 1.1774, floor_px);
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
    };

    // RMS per coordinate of each kind of observation at the state s.
    struct ObservationNoise {
        double camera = 1, projector = 1, dense = 1;
    };
    const auto square = [](double v) { return v * v; };
    // Exact simulated data would give infinite weights; no calibration is
    // better than a thousandth of a pixel.
    const auto noise_floor = [](double sigma) {
        return std::isfinite(sigma) ? std::max(sigma, 1e-3) : 1.0;
    };
    const auto observation_noise = [&](const detail::RigState& at) {
        StereoCalibration model;
        model.camera = at.camera;
        model.camera_correction = at.camera_grid;
        model.projector = at.projector;
        model.projector_correction = at.projector_grid;
        model.R = at.R;
        model.T = at.T;
        double sc = 0, sp = 0, sd = 0;
        std::size_t nc = 0, np = 0;
        for (const detail::CornerObservation& o : corners) {
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
        for (const detail::DenseObservation& o : dense) {
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
    };

    std::vector<bool> used(poses.size(), true);
    detail::AdjustmentOutcome camera_outcome, projector_outcome;
    // What the last adjustments held free, with their weights: the
    // covariance is theirs.
    detail::FreeParameters camera_free, projector_free;
    for (int round = 0; round < 2; ++round) {
        if (round == 1)
            s = initial; // again from the start, without the outlying poses
        if (camera_first) {
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
            detail::FreeParameters free;
            free.camera_lens = free.poses = free.camera_observations = true;
            free.camera_grid = !s.camera_grid.empty();
            free.skew = options.skew;
            free.camera_weight = 1 / square(noise.camera);
            if (free.camera_grid && options.camera_grid_smoothness == 0) {
                StageTimer validation(result.time_split, "camera grid cross-validation");
                regularisation.camera_smoothness =
                    choose_camera_smoothness(s, corners, used, free, regularisation, options, pool,
                                             result.camera_grid_validation);
            }
            result.camera_grid_smoothness = regularisation.camera_smoothness;
            StageTimer camera_stage(result.time_split, "camera adjustment");
            camera_outcome = detail::adjust(s, corners, {}, used, free, regularisation,
                                            options.max_iterations, options.progress, &pool);
            camera_stage.stop();
            camera_free = free;
            if (options.camera_focal_scale != 1) {
                say("the camera's focal lengths scaled by " +
                    std::to_string(options.camera_focal_scale) +
                    " (a depth scale measured elsewhere), the boards placed again");
                scale_focal_lengths(s.camera, options.camera_focal_scale);
                detail::FreeParameters place;
                place.poses = place.camera_observations = true;
                place.camera_weight = free.camera_weight;
                detail::adjust(s, corners, {}, used, place, regularisation, options.max_iterations,
                               options.progress, &pool);
            }
            say("the projector with the camera and the boards held, from its corners "
                "(intrinsics, distortion, R, T)");
            free = {};
            free.projector_lens = free.stereo = free.projector_observations = true;
            free.skew = options.skew;
            free.projector_weight = 1 / square(noise.projector);
            StageTimer projector_stage(result.time_split, "projector adjustment (corners)");
            projector_outcome = detail::adjust(s, corners, {}, used, free, regularisation,
                                               options.max_iterations, options.progress, &pool);
            projector_stage.stop();
            result.iterations += camera_outcome.iterations + projector_outcome.iterations;
            // Then with the dense samples and the grid. Samples off the
            // model (decoded to the wrong fringe, the board's edge against a
            // wall behind it, a speck on the board) are dropped first against
            // the corners' model, then once more against the dense one:
            // squared residuals would let a few of them bend the projector.
            StageTimer dense_stage(result.time_split, "projector adjustment (dense samples)");
            place_dense_samples(used);
            if (!dense.empty() || !s.projector_grid.empty()) {
                const std::size_t placed = dense.size();
                // Loose against the corners' model, which lacks the grid:
                // only samples decoded to the wrong fringe go.
                const std::size_t dropped = drop_dense_outliers(10, 5);
                say("the projector again with " + std::to_string(dense.size()) +
                    " dense samples of the boards' bright parts (" + std::to_string(dropped) +
                    " of " + std::to_string(placed) + " off the corners' model dropped)" +
                    (s.projector_grid.empty() ? "" : " and its correction grid"));
                free.projector_grid = !s.projector_grid.empty();
                noise = observation_noise(s);
                free.projector_weight = 1 / square(noise.projector);
                free.dense_weight = 1 / square(noise.dense);
                projector_outcome = detail::adjust(s, corners, dense, used, free, regularisation,
                                                   options.max_iterations, options.progress, &pool);
                result.iterations += projector_outcome.iterations;
                // Weighted again by the residuals of the grid's model, and
                // without the samples that are still off it.
                const std::size_t again = drop_dense_outliers(5, 0.5);
                say("  again with the residuals' weights" +
                    (again
                         ? " and without " + std::to_string(again) + " dense samples off the model"
                         : std::string()));
                noise = observation_noise(s);
                free.projector_weight = 1 / square(noise.projector);
                free.dense_weight = 1 / square(noise.dense);
                projector_outcome = detail::adjust(s, corners, dense, used, free, regularisation,
                                                   options.max_iterations, options.progress, &pool);
                result.iterations += projector_outcome.iterations;
            }
            dense_stage.stop();
            projector_free = free;
        } else {
            say(round == 0 ? "joint bundle adjustment (both devices, skew " +
                                 std::string(options.skew ? "estimated" : "fixed at 0") + ")"
                           : "bundle adjustment again without the outlying poses");
            detail::FreeParameters free;
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
                free.camera_weight =
                    1 / square(noise_floor(result.initial_camera_rms / std::sqrt(2.0)));
                free.projector_weight =
                    1 / square(noise_floor(result.initial_projector_rms / std::sqrt(2.0)));
            }
            // The camera grid's stiffness is the camera lens's: chosen as in
            // camera_first, from the camera's corners alone (left at 0, the
            // grid would be held by its ridge only and trade with the focal
            // lengths and the poses: 2 % of aspect ratio on 6 real poses).
            if (free.camera_grid && options.camera_grid_smoothness == 0) {
                detail::FreeParameters camera_only;
                camera_only.camera_lens = camera_only.camera_grid = camera_only.poses = true;
                camera_only.camera_observations = true;
                camera_only.skew = options.skew;
                camera_only.camera_weight = free.camera_weight;
                StageTimer validation(result.time_split, "camera grid cross-validation");
                regularisation.camera_smoothness =
                    choose_camera_smoothness(s, corners, used, camera_only, regularisation, options,
                                             pool, result.camera_grid_validation);
            }
            result.camera_grid_smoothness = regularisation.camera_smoothness;
            StageTimer joint_stage(result.time_split, "joint adjustment");
            camera_outcome = detail::adjust(s, corners, {}, used, free, regularisation,
                                            options.max_iterations, options.progress, &pool);
            if (grids) {
                const ObservationNoise noise = observation_noise(s);
                free.camera_weight = 1 / square(noise.camera);
                free.projector_weight = 1 / square(noise.projector);
                camera_outcome = detail::adjust(s, corners, {}, used, free, regularisation,
                                                options.max_iterations, options.progress, &pool);
            }
            projector_outcome = camera_outcome;
            result.iterations += camera_outcome.iterations;
            camera_free = projector_free = free;
        }

        // Per-pose residuals and outliers among the used poses.
        StageTimer residuals_stage(result.time_split, "residuals");
        StereoCalibration& c = result.calibration;
        c.camera_size = camera_size;
        c.projector_size = projector_size;
        c.camera = s.camera;
        c.projector = s.projector;
        c.camera_correction = s.camera_grid;
        c.projector_correction = s.projector_grid;
        c.R = s.R;
        c.T = s.T;
        result.camera_residuals.assign(poses.size(), {});
        result.projector_residuals.assign(poses.size(), {});
        std::vector<double> combined;
        std::vector<PoseRms> rms(poses.size());
        for (std::size_t i = 0; i < poses.size(); ++i) {
            const PoseObservations& o = poses[i];
            for (std::size_t k = 0; k < o.board.size(); ++k) {
                const Vec2 uc = project_camera(c, s.poses[i], o.board[k]);
                result.camera_residuals[i].push_back(
                    {uc[0] - o.camera[k][0], uc[1] - o.camera[k][1]});
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
        detail::place_dense_points(s, dense);
        for (std::size_t k = 0; k < dense.size(); ++k) {
            const Vec2 up = c.projector_pixel(dense[k].camera_point);
            const Vec2 e{up[0] - dense[k].projector[0], up[1] - dense[k].projector[1]};
            result.dense_residuals[std::size_t(dense_origin[k].first)]
                                  [std::size_t(dense_origin[k].second)] = e;
            dense_sum += e[0] * e[0] + e[1] * e[1];
        }
        result.dense_rms = dense.empty() ? -1 : std::sqrt(dense_sum / double(dense.size()));
        std::vector<double> sorted = combined;
        std::sort(sorted.begin(), sorted.end());
        const double median = sorted.empty() ? 0 : sorted[sorted.size() / 2];
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
        const auto sigmas = [&](const detail::AdjustmentOutcome& o, int device, LensModel& out) {
            const int dof = o.residuals - o.parameters;
            if (dof <= 0)
                return;
            const double variance = o.data_cost / dof;
            double sg[detail::kLensParameters];
            for (int k = 0; k < detail::kLensParameters; ++k)
                sg[k] = std::sqrt(
                    o.lens_variance[std::size_t(device * detail::kLensParameters + k)] * variance);
            out = LensModel{sg[0], sg[1], sg[2], sg[3], sg[4], sg[5], sg[6], sg[9], sg[7], sg[8]};
        };
        sigmas(camera_outcome, 0, result.camera_sigma);
        sigmas(projector_outcome, 1, result.projector_sigma);

        if (round == 0 && options.drop_outliers && !result.outliers.empty()) {
            const int remaining = static_cast<int>(combined.size() - result.outliers.size());
            if (remaining < 3) {
                say("not dropping the outliers: fewer than 3 poses would remain");
                break;
            }
            for (int i : result.outliers)
                used[static_cast<std::size_t>(i)] = false;
            continue;
        }
        break;
    }
    result.board_poses = s.poses;
    predict_from_covariance(result, s, corners, dense, used, camera_free, projector_free,
                            regularisation, camera_first, poses, options, pool, say);
    return result;
}

} // namespace fpp::calib
