// Stereo calibration: OpenCV initialisation, then a joint Levenberg-Marquardt
// bundle adjustment over both devices' intrinsics (with skew), distortion,
// the camera-to-projector transform and every board pose.

#include "fpp/calib/stereo_calibrate.hpp"

#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace fpp::calib {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Lens parameters in the state: fu fv cu cv skew k1 k2 p1 p2 k3.
constexpr int kLens = 10;
constexpr int kSkew = 4;
constexpr int kGlobal = 2 * kLens + 6; // camera, projector, stereo rotation and translation
constexpr int kPerPose = 6;
using LensParams = std::array<double, kLens>;

LensParams to_params(const LensModel& l) {
    return {l.fu, l.fv, l.cu, l.cv, l.skew, l.k1, l.k2, l.p1, l.p2, l.k3};
}

LensModel to_lens(const LensParams& p) {
    LensModel l;
    l.fu = p[0];
    l.fv = p[1];
    l.cu = p[2];
    l.cv = p[3];
    l.skew = p[4];
    l.k1 = p[5];
    l.k2 = p[6];
    l.p1 = p[7];
    l.p2 = p[8];
    l.k3 = p[9];
    return l;
}

// Central-difference steps per lens parameter (pixels for the linear part,
// unitless for distortion).
constexpr double kLensStep[kLens] = {1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-6, 1e-6, 1e-7, 1e-7, 1e-6};
constexpr double kRotationStep = 1e-7;    // rad
constexpr double kTranslationStep = 1e-5; // mm

struct State {
    LensParams camera{};
    LensParams projector{};
    Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Vec3 T{0, 0, 0};
    std::vector<RigidPose> poses;
};

Vec3 add(const Vec3& a, const Vec3& b) {
    return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}

// R <- exp([w]x) R
Mat3 rotate(const Mat3& R, const Vec3& w) {
    return mul(rotation_from_vector(w), R);
}

// Adds component `index` of a full increment (layout: camera lens, projector
// lens, stereo rotation, stereo translation, then per pose rotation and
// translation) scaled by `amount`.
void perturb(State& s, int index, double amount) {
    if (index < kLens) {
        s.camera[static_cast<std::size_t>(index)] += amount;
    } else if (index < 2 * kLens) {
        s.projector[static_cast<std::size_t>(index - kLens)] += amount;
    } else if (index < 2 * kLens + 3) {
        Vec3 w{0, 0, 0};
        w[static_cast<std::size_t>(index - 2 * kLens)] = amount;
        s.R = rotate(s.R, w);
    } else if (index < kGlobal) {
        s.T[static_cast<std::size_t>(index - 2 * kLens - 3)] += amount;
    } else {
        const int pose = (index - kGlobal) / kPerPose, c = (index - kGlobal) % kPerPose;
        RigidPose& p = s.poses[static_cast<std::size_t>(pose)];
        if (c < 3) {
            Vec3 w{0, 0, 0};
            w[static_cast<std::size_t>(c)] = amount;
            p.R = rotate(p.R, w);
        } else {
            p.t[static_cast<std::size_t>(c - 3)] += amount;
        }
    }
}

double step_for(int index) {
    if (index < 2 * kLens)
        return kLensStep[index % kLens];
    if (index < 2 * kLens + 3)
        return kRotationStep;
    if (index < kGlobal)
        return kTranslationStep;
    return ((index - kGlobal) % kPerPose) < 3 ? kRotationStep : kTranslationStep;
}

class Problem {
  public:
    Problem(const std::vector<PoseObservations>& obs, const std::vector<bool>& used, bool skew)
        : obs_(obs), used_(used) {
        const int n = static_cast<int>(obs.size());
        row_offset_.assign(obs.size() + 1, 0);
        for (int i = 0; i < n; ++i) {
            int rows = 0;
            if (used[static_cast<std::size_t>(i)]) {
                const PoseObservations& o = obs[static_cast<std::size_t>(i)];
                for (std::size_t k = 0; k < o.board.size(); ++k)
                    rows += 2 + (projector_valid(o, k) ? 2 : 0);
            }
            row_offset_[static_cast<std::size_t>(i) + 1] =
                row_offset_[static_cast<std::size_t>(i)] + rows;
        }
        // Free parameters: everything but fixed skew and the poses left out.
        for (int p = 0; p < kGlobal + kPerPose * n; ++p) {
            if (!skew && (p == kSkew || p == kLens + kSkew))
                continue;
            if (p >= kGlobal && !used[static_cast<std::size_t>((p - kGlobal) / kPerPose)])
                continue;
            free_.push_back(p);
        }
    }

    static bool projector_valid(const PoseObservations& o, std::size_t k) {
        return std::isfinite(o.projector[k][0]) && std::isfinite(o.projector[k][1]);
    }

    int rows() const { return row_offset_.back(); }
    int cols() const { return static_cast<int>(free_.size()); }
    const std::vector<int>& free() const { return free_; }

    // Residuals (predicted - measured) of pose i into r[row_offset(i) ...].
    void pose_residuals(const State& s, int i, double* r) const {
        const PoseObservations& o = obs_[static_cast<std::size_t>(i)];
        const RigidPose& pose = s.poses[static_cast<std::size_t>(i)];
        const LensModel cam = to_lens(s.camera), proj = to_lens(s.projector);
        double* out = r + row_offset_[static_cast<std::size_t>(i)];
        for (std::size_t k = 0; k < o.board.size(); ++k) {
            const Vec3 xc = add(mul(pose.R, o.board[k]), pose.t);
            const Vec2 uc = cam.project(xc);
            *out++ = uc[0] - o.camera[k][0];
            *out++ = uc[1] - o.camera[k][1];
            if (projector_valid(o, k)) {
                const Vec2 up = proj.project(add(mul(s.R, xc), s.T));
                *out++ = up[0] - o.projector[k][0];
                *out++ = up[1] - o.projector[k][1];
            }
        }
    }

    void residuals(const State& s, Eigen::VectorXd& r) const {
        r.resize(rows());
        for (std::size_t i = 0; i < obs_.size(); ++i)
            if (used_[i])
                pose_residuals(s, static_cast<int>(i), r.data());
    }

    // Central-difference Jacobian over the free parameters; pose parameters
    // touch their own pose's rows only.
    void jacobian(const State& s, Eigen::MatrixXd& J) const {
        J.setZero(rows(), cols());
        Eigen::VectorXd rp(rows()), rm(rows());
        for (int c = 0; c < cols(); ++c) {
            const int p = free_[static_cast<std::size_t>(c)];
            const double h = step_for(p);
            State sp = s, sm = s;
            perturb(sp, p, h);
            perturb(sm, p, -h);
            if (p < kGlobal) {
                residuals(sp, rp);
                residuals(sm, rm);
                J.col(c) = (rp - rm) / (2 * h);
            } else {
                const int i = (p - kGlobal) / kPerPose;
                pose_residuals(sp, i, rp.data());
                pose_residuals(sm, i, rm.data());
                const int r0 = row_offset_[static_cast<std::size_t>(i)];
                const int nr = row_offset_[static_cast<std::size_t>(i) + 1] - r0;
                J.col(c).segment(r0, nr) = (rp.segment(r0, nr) - rm.segment(r0, nr)) / (2 * h);
            }
        }
    }

    void apply(State& s, const Eigen::VectorXd& delta) const {
        // Global and pose blocks: rotations as one rotation vector each.
        std::vector<double> full(
            static_cast<std::size_t>(kGlobal + kPerPose * static_cast<int>(obs_.size())), 0.0);
        for (int c = 0; c < cols(); ++c)
            full[static_cast<std::size_t>(free_[static_cast<std::size_t>(c)])] = delta(c);
        for (int k = 0; k < kLens; ++k) {
            s.camera[static_cast<std::size_t>(k)] += full[static_cast<std::size_t>(k)];
            s.projector[static_cast<std::size_t>(k)] += full[static_cast<std::size_t>(kLens + k)];
        }
        s.R = rotate(s.R, {full[2 * kLens], full[2 * kLens + 1], full[2 * kLens + 2]});
        s.T = add(s.T, {full[2 * kLens + 3], full[2 * kLens + 4], full[2 * kLens + 5]});
        for (std::size_t i = 0; i < obs_.size(); ++i) {
            const std::size_t b = static_cast<std::size_t>(kGlobal) + kPerPose * i;
            s.poses[i].R = rotate(s.poses[i].R, {full[b], full[b + 1], full[b + 2]});
            s.poses[i].t = add(s.poses[i].t, {full[b + 3], full[b + 4], full[b + 5]});
        }
    }

  private:
    const std::vector<PoseObservations>& obs_;
    std::vector<bool> used_;
    std::vector<int> row_offset_;
    std::vector<int> free_;
};

struct LmOutcome {
    int iterations = 0;
    Eigen::MatrixXd JtJ; // at the solution, free parameters
    double cost = 0;     // sum of squared residuals
};

LmOutcome levenberg_marquardt(const Problem& problem, State& s, int max_iterations,
                              const std::function<void(const std::string&)>& progress) {
    LmOutcome out;
    Eigen::VectorXd r, r_new;
    Eigen::MatrixXd J;
    problem.residuals(s, r);
    double cost = r.squaredNorm();
    double lambda = 1e-3;
    const double rows = std::max(1, problem.rows());
    for (int it = 0; it < max_iterations; ++it) {
        problem.jacobian(s, J);
        const Eigen::MatrixXd A = J.transpose() * J;
        const Eigen::VectorXd g = J.transpose() * r;
        // Scale to unit diagonal (parameters span focal lengths of thousands
        // of pixels and distortion terms of 1e-4).
        Eigen::VectorXd d = A.diagonal().cwiseSqrt();
        for (Eigen::Index k = 0; k < d.size(); ++k)
            if (!(d(k) > 0))
                d(k) = 1;
        const Eigen::MatrixXd As = d.asDiagonal().inverse() * A * d.asDiagonal().inverse();
        const Eigen::VectorXd gs = d.asDiagonal().inverse() * g;
        bool accepted = false;
        double step_norm = 0;
        for (int attempt = 0; attempt < 20 && !accepted; ++attempt) {
            Eigen::MatrixXd M = As;
            M.diagonal().array() += lambda;
            const Eigen::LDLT<Eigen::MatrixXd> ldlt(M);
            const Eigen::VectorXd step_s = -ldlt.solve(gs);
            const Eigen::VectorXd step = d.asDiagonal().inverse() * step_s;
            if (!step.allFinite()) {
                lambda *= 10;
                continue;
            }
            State trial = s;
            problem.apply(trial, step);
            problem.residuals(trial, r_new);
            const double cost_new =
                r_new.allFinite() ? r_new.squaredNorm() : std::numeric_limits<double>::infinity();
            if (cost_new < cost) {
                s = std::move(trial);
                const double decrease = (cost - cost_new) / cost;
                cost = cost_new;
                r = r_new;
                lambda = std::max(lambda / 3, 1e-12);
                accepted = true;
                step_norm = step_s.norm();
                out.iterations = it + 1;
                if (progress && (it < 3 || it % 5 == 0)) {
                    std::ostringstream msg;
                    msg.precision(4);
                    msg << "  LM iteration " << it + 1 << ": RMS residual "
                        << std::sqrt(cost / rows) << " px (per coordinate), lambda " << lambda;
                    progress(msg.str());
                }
                if (decrease < 1e-12 || step_norm < 1e-10)
                    it = max_iterations; // converged
            } else {
                lambda *= 4;
            }
        }
        if (!accepted)
            break; // no decrease possible: at the minimum to rounding
    }
    problem.jacobian(s, J);
    out.JtJ = J.transpose() * J;
    out.cost = cost;
    return out;
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

Vec2 project_camera(const StereoCalibration& c, const RigidPose& pose, const Vec3& board) {
    return c.camera.project(add(mul(pose.R, board), pose.t));
}

Vec2 project_projector(const StereoCalibration& c, const RigidPose& pose, const Vec3& board) {
    const Vec3 xc = add(mul(pose.R, board), pose.t);
    return c.projector.project(add(mul(c.R, xc), c.T));
}

StereoResult stereo_calibrate(const std::vector<PoseObservations>& poses, Size camera_size,
                              Size projector_size, const StereoOptions& options) {
    const auto say = [&](const std::string& s) {
        if (options.progress)
            options.progress(s);
    };
    if (poses.size() < 3)
        throw std::invalid_argument("stereo calibration needs at least 3 poses, got " +
                                    std::to_string(poses.size()));
    for (const PoseObservations& p : poses) {
        if (p.board.size() != p.camera.size() || p.board.size() != p.projector.size())
            throw std::invalid_argument("pose " + p.name + ": point counts differ");
        int both = 0;
        for (std::size_t k = 0; k < p.board.size(); ++k)
            both += Problem::projector_valid(p, k) ? 1 : 0;
        if (both < 4)
            throw std::invalid_argument("pose " + p.name +
                                        ": fewer than 4 corners seen by both devices");
    }

    // OpenCV initialisation (skew 0, 5 distortion coefficients).
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
            if (Problem::projector_valid(p, k)) {
                obj_s.back().push_back(b);
                img_cs.back().push_back(c);
                img_ps.back().emplace_back(static_cast<float>(p.projector[k][0]),
                                           static_cast<float>(p.projector[k][1]));
            }
        }
    }
    StereoResult result;
    result.skew_estimated = options.skew;
    cv::Mat Kc, Dc, Kp, Dp, Rs, Ts, E, F;
    std::vector<cv::Mat> rvecs, tvecs, rvecs_p, tvecs_p;
    const cv::TermCriteria criteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200,
                                    DBL_EPSILON);
    try {
        say("initialising the camera (OpenCV calibrateCamera)");
        result.initial_camera_rms =
            cv::calibrateCamera(obj_c, img_c, cv::Size(camera_size.width, camera_size.height), Kc,
                                Dc, rvecs, tvecs, 0, criteria);
        say("initialising the projector (OpenCV calibrateCamera)");
        result.initial_projector_rms = cv::calibrateCamera(
            obj_s, img_ps, cv::Size(projector_size.width, projector_size.height), Kp, Dp, rvecs_p,
            tvecs_p, 0, criteria);
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
        msg << "  OpenCV initial RMS: camera " << result.initial_camera_rms << " px, projector "
            << result.initial_projector_rms << " px";
        say(msg.str());
    }

    State s;
    s.camera = to_params(lens_from_cv(Kc, Dc));
    s.projector = to_params(lens_from_cv(Kp, Dp));
    s.R = from_cv_rotation(Rs);
    s.T = from_cv_vec(Ts);
    for (std::size_t i = 0; i < poses.size(); ++i)
        s.poses.push_back({from_cv_rotation(rvecs[i]), from_cv_vec(tvecs[i])});

    std::vector<bool> used(poses.size(), true);
    LmOutcome lm;
    for (int round = 0; round < 2; ++round) {
        say(round == 0 ? "joint bundle adjustment (both devices, skew " +
                             std::string(options.skew ? "estimated" : "fixed at 0") + ")"
                       : "bundle adjustment again without the outlying poses");
        const Problem problem(poses, used, options.skew);
        lm = levenberg_marquardt(problem, s, options.max_iterations, options.progress);
        result.iterations += lm.iterations;

        // Per-pose residuals and outliers among the used poses.
        const LensModel cam = to_lens(s.camera), proj = to_lens(s.projector);
        result.camera_residuals.assign(poses.size(), {});
        result.projector_residuals.assign(poses.size(), {});
        std::vector<double> combined;
        std::vector<PoseRms> rms(poses.size());
        for (std::size_t i = 0; i < poses.size(); ++i) {
            const PoseObservations& o = poses[i];
            for (std::size_t k = 0; k < o.board.size(); ++k) {
                const Vec3 xc = add(mul(s.poses[i].R, o.board[k]), s.poses[i].t);
                const Vec2 uc = cam.project(xc);
                result.camera_residuals[i].push_back(
                    {uc[0] - o.camera[k][0], uc[1] - o.camera[k][1]});
                if (Problem::projector_valid(o, k)) {
                    const Vec2 up = proj.project(add(mul(s.R, xc), s.T));
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
        std::vector<double> sorted = combined;
        std::sort(sorted.begin(), sorted.end());
        const double median = sorted.empty() ? 0 : sorted[sorted.size() / 2];
        result.outliers.clear();
        for (std::size_t i = 0; i < poses.size(); ++i)
            if (used[i] && rms[i].combined > options.outlier_factor * median)
                result.outliers.push_back(static_cast<int>(i));

        StereoCalibration& c = result.calibration;
        c.camera_size = camera_size;
        c.projector_size = projector_size;
        c.camera = cam;
        c.projector = proj;
        c.R = s.R;
        c.T = s.T;
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

        // Uncertainties: covariance = (J^T J)^-1 * residual variance.
        result.camera_sigma = to_lens(LensParams{});
        result.projector_sigma = result.camera_sigma;
        const int dof = problem.rows() - problem.cols();
        if (dof > 0) {
            const double variance = lm.cost / dof;
            const Eigen::MatrixXd cov =
                lm.JtJ.ldlt().solve(Eigen::MatrixXd::Identity(lm.JtJ.rows(), lm.JtJ.cols())) *
                variance;
            LensParams sc_params{}, sp_params{};
            for (int col = 0; col < problem.cols(); ++col) {
                const int p = problem.free()[static_cast<std::size_t>(col)];
                const double sigma = std::sqrt(std::max(0.0, cov(col, col)));
                if (p < kLens)
                    sc_params[static_cast<std::size_t>(p)] = sigma;
                else if (p < 2 * kLens)
                    sp_params[static_cast<std::size_t>(p - kLens)] = sigma;
            }
            result.camera_sigma = to_lens(sc_params);
            result.projector_sigma = to_lens(sp_params);
        }

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
    return result;
}

} // namespace fpp::calib
