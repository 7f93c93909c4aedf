// Hybrid calibration: per-pose SV planes, correction onto them, per-pixel
// cubic fits into a coefficient table.

#include "fpp/calib/hybrid_calibrate.hpp"

#include "fpp/calib/session_folder.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/enum_names.hpp"
#include "fpp/error.hpp"
#include "fpp/parallel.hpp"
#include "fpp/point_cloud.hpp"
#include "hybrid_fit.hpp"
#include "phase_smoothing.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace fpp::calib {

namespace fs = std::filesystem;

namespace {

double since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string size_text(Size s) {
    return std::to_string(s.width) + " x " + std::to_string(s.height);
}

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Least-squares plane of the listed points (orthogonal distances): the
// centroid and the covariance's eigenvector of least eigenvalue.
bool least_squares_plane(const float* p, const std::vector<std::size_t>& points,
                         BoardPlane& plane) {
    if (points.size() < 3)
        return false;
    // Shifted by the first point for conditioning (coordinates ~500 mm).
    const std::size_t first = points.front();
    const Eigen::Vector3d origin{double(p[3 * first]), double(p[3 * first + 1]),
                                 double(p[3 * first + 2])};
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
    for (const std::size_t i : points) {
        const Eigen::Vector3d r =
            Eigen::Vector3d{double(p[3 * i]), double(p[3 * i + 1]), double(p[3 * i + 2])} - origin;
        sum += r;
        outer += r * r.transpose();
    }
    const auto count = double(points.size());
    const Eigen::Vector3d mean = sum / count;
    const Eigen::Matrix3d cov = outer / count - mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    if (eig.info() != Eigen::Success)
        return false;
    const Eigen::Vector3d values = eig.eigenvalues(); // ascending
    // A line of points (or one point) fixes no plane.
    if (!(values[1] > 1e-9 * values[2]) || !(values[2] > 0))
        return false;
    Eigen::Vector3d normal = eig.eigenvectors().col(0).normalized();
    if (normal.z() < 0)
        normal = -normal;
    const Eigen::Vector3d centroid = origin + mean;
    plane.normal = {normal.x(), normal.y(), normal.z()};
    plane.d = normal.dot(centroid);
    return std::isfinite(plane.d);
}

double signed_distance(const BoardPlane& plane, const float* q) {
    return plane.normal[0] * double(q[0]) + plane.normal[1] * double(q[1]) +
           plane.normal[2] * double(q[2]) - plane.d;
}

float percentile(std::vector<float> values, double q) {
    if (values.empty())
        return kNaN;
    const auto k = static_cast<std::ptrdiff_t>(q * double(values.size() - 1));
    std::nth_element(values.begin(), values.begin() + k, values.end());
    return values[static_cast<std::size_t>(k)];
}

} // namespace

constexpr EnumName<HybridSamples> kHybridSamplesNames[] = {
    {HybridSamples::boards_and_model, "boards+model"},
    {HybridSamples::boards, "boards"},
    {HybridSamples::model, "model"},
};

const char* to_string(HybridSamples samples) {
    return name_of(kHybridSamplesNames, samples);
}

HybridSamples parse_hybrid_samples(const std::string& name) {
    return parse_name(kHybridSamplesNames, "samples", name);
}

void HybridOptions::validate() const {
    auto bad = [](const std::string& field, const std::string& why) {
        throw std::invalid_argument("hybrid option " + field + ": " + why);
    };
    if (min_poses < 4)
        bad("min_poses", "a cubic needs at least 4 poses per pixel");
    if (phase_smoothing_radius < 0 || phase_smoothing_radius > 50)
        bad("phase_smoothing_radius", "must be in [0, 50] px");
    if (!(max_condition >= 10))
        bad("max_condition", "must be at least 10");
    if (!(outlier_sigmas > 0))
        bad("outlier_sigmas", "must be positive");
    if (!(outlier_floor_mm >= 0))
        bad("outlier_floor_mm", "must not be negative");
    if (!(max_outlier_fraction >= 0 && max_outlier_fraction < 1))
        bad("max_outlier_fraction", "must be in [0, 1)");
    if (!(min_pose_coverage > 0 && min_pose_coverage <= 1))
        bad("min_pose_coverage", "must be in (0, 1]");
    if (min_usable_poses < 4)
        bad("min_usable_poses", "at least 4 plane poses are needed for a cubic");
    if (threads < 0)
        bad("threads", "must not be negative");
    if (min_board_samples < 2)
        bad("min_board_samples", "at least 2 board samples show a pixel's depth range");
    if (model_samples < 2 || model_samples > 64)
        bad("model_samples", "must be in [2, 64]");
    if (!(model_depth_margin_mm >= 0 && model_depth_margin_mm <= 100))
        bad("model_depth_margin_mm", "must be in [0, 100] mm");
    if (!(max_sample_deviation_px > 0))
        bad("max_sample_deviation_px", "must be positive");
    if (!(min_lit_fraction > 0 && min_lit_fraction <= 1))
        bad("min_lit_fraction", "must be in (0, 1]");
    if (!(square_size_tolerance > 0 && square_size_tolerance < 0.5))
        bad("square_size_tolerance", "must be in (0, 0.5)");
    bright.validate();
}

bool fit_board_plane(Image<float>& xyz, const HybridOptions& options, BoardPlane& plane,
                     PlaneFitStats& stats, bool drop_outliers) {
    const std::size_t n = xyz.pixel_count();
    float* p = xyz.data();
    std::vector<std::size_t> valid;
    valid.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
        if (std::isfinite(p[3 * i]) && std::isfinite(p[3 * i + 1]) && std::isfinite(p[3 * i + 2]))
            valid.push_back(i);
    // The robust search runs on a spread-out sample of at most ~100k points
    // (as good as all of them for a plane and its thresholds, and 20 times
    // cheaper at full size); every point is then classified once.
    const std::size_t stride = std::max<std::size_t>(1, valid.size() / 100000);
    std::vector<std::size_t> sample;
    for (std::size_t k = 0; k < valid.size(); k += stride)
        sample.push_back(valid[k]);
    BoardPlane fitted;
    if (!least_squares_plane(p, sample, fitted))
        return false;
    std::vector<float> abs_dist(sample.size());
    std::vector<std::size_t> kept, previous;
    // Keeps the sample points within `limit` of the plane (all of them when
    // `limit` is negative: the median is taken first) and refits.
    auto refit = [&](double sigmas, double floor_mm) {
        for (std::size_t k = 0; k < sample.size(); ++k)
            abs_dist[k] = static_cast<float>(std::fabs(signed_distance(fitted, p + 3 * sample[k])));
        const double median = double(percentile(abs_dist, 0.5));
        const double limit = sigmas > 0 ? std::max(sigmas * 1.4826 * median, floor_mm) : median;
        previous.swap(kept);
        kept.clear();
        for (std::size_t k = 0; k < sample.size(); ++k)
            if (double(abs_dist[k]) <= limit)
                kept.push_back(sample[k]);
        return least_squares_plane(p, kept, fitted);
    };
    // Least trimmed squares first (concentration steps on the better half):
    // a plain least-squares start lies between the board and whatever stands
    // on it (a box covering a quarter of the image), and a threshold from
    // its residuals would keep both.
    for (int round = 0; round < 10; ++round) {
        if (!refit(0, 0))
            return false;
        if (kept == previous)
            break;
    }
    // Then every point within max(k sigma, floor) of the plane, refitted until
    // the inlier set settles.
    for (int round = 0; round < 8; ++round) {
        if (!refit(options.outlier_sigmas, options.outlier_floor_mm))
            return false;
        if (kept == previous)
            break;
    }
    // All points: the same threshold, one least-squares fit of the inliers.
    for (std::size_t k = 0; k < sample.size(); ++k)
        abs_dist[k] = static_cast<float>(std::fabs(signed_distance(fitted, p + 3 * sample[k])));
    const double limit =
        std::max(options.outlier_sigmas * 1.4826 * double(percentile(abs_dist, 0.5)),
                 options.outlier_floor_mm);
    kept.clear();
    for (const std::size_t i : valid)
        if (std::fabs(signed_distance(fitted, p + 3 * i)) <= limit)
            kept.push_back(i);
    if (!least_squares_plane(p, kept, fitted))
        return false;
    stats = {};
    stats.points = valid.size();
    double sum2 = 0;
    std::size_t inliers = 0;
    for (const std::size_t i : valid) {
        const double dist = signed_distance(fitted, p + 3 * i);
        if (std::fabs(dist) > limit) {
            ++stats.outliers;
            if (drop_outliers)
                p[3 * i] = p[3 * i + 1] = p[3 * i + 2] = kNaN;
            continue;
        }
        sum2 += dist * dist;
        stats.max_mm = std::max(stats.max_mm, std::fabs(dist));
        ++inliers;
    }
    stats.rms_mm = inliers ? std::sqrt(sum2 / double(inliers)) : 0.0;
    plane = fitted;
    return true;
}

std::string HybridResult::summary() const {
    std::ostringstream s;
    s.setf(std::ios::fixed);
    s.precision(4);
    const TableInfo& info = table.info();
    const bool checkerboard = board == BoardDescription::Kind::checkerboard;
    s << "hybrid model: " << to_string(info.model) << ", camera " << size_text(info.camera)
      << ", tiles " << info.tile_width << " x " << info.tile_height << "\n";
    if (checkerboard)
        s << "procedure: checkerboards placed by the camera; fitted to " << to_string(samples)
          << "\n";
    else
        s << "procedure: flat boards placed by SV (the paper's)\n";
    s << "poses: " << usable_poses << " of " << poses.size() << " used\n";
    for (const HybridPose& p : poses) {
        s << "  " << p.name << ": ";
        if (!p.usable)
            s << "rejected: " << p.skip_reason << "\n";
        else if (checkerboard)
            s << "board at " << std::setprecision(1) << p.distance_mm << " mm, tilt " << p.tilt_deg
              << " deg, corners " << std::setprecision(4) << p.corner_rms_px << " px, " << p.samples
              << " samples; SV plane " << std::setprecision(4) << p.sv_offset_mm << " mm, "
              << p.sv_angle_deg << " deg from the camera's, SV RMS " << p.plane_rms_mm
              << " mm about it\n";
        else
            s << p.points << " points, plane at " << std::setprecision(1) << p.distance_mm
              << " mm, tilt " << p.tilt_deg << " deg, plane RMS " << std::setprecision(4)
              << p.plane_rms_mm << " mm, max " << p.plane_max_mm << " mm, " << p.outliers
              << " outliers\n";
    }
    const std::size_t total = pose_count.pixel_count();
    s << "pixels modelled: " << pixels_modelled << " of " << total << " (" << std::setprecision(2)
      << (total ? 100.0 * double(pixels_modelled) / double(total) : 0.0) << " %); too few poses "
      << pixels_too_few_poses << ", ill-conditioned " << pixels_ill_conditioned << "\n";
    s.precision(4);
    auto line = [&](const char* name, const Image<float>& rms) {
        std::vector<float> v;
        v.reserve(rms.pixel_count());
        for (std::size_t i = 0; i < rms.pixel_count(); ++i)
            if (std::isfinite(rms.data()[i]))
                v.push_back(rms.data()[i]);
        s << "fit RMS " << name << " (mm): median " << percentile(v, 0.5) << ", 99 % "
          << percentile(v, 0.99) << ", max " << percentile(v, 1.0) << "\n";
    };
    line("X", rms_x);
    line("Y", rms_y);
    line("Z", rms_z);
    {
        std::vector<float> v;
        for (std::size_t i = 0; i < sigma_z.pixel_count(); ++i)
            if (std::isfinite(sigma_z.data()[i]))
                v.push_back(sigma_z.data()[i]);
        s << "predicted depth sigma of the table (mm): median " << percentile(v, 0.5) << ", 99 % "
          << percentile(v, 0.99) << "\n";
    }
    s << "time: poses " << std::setprecision(2) << seconds_poses << " s, fit " << seconds_fit
      << " s, total " << seconds_total << " s\n";
    return s.str();
}

HybridResult calibrate_hybrid(const fs::path& session, const StereoCalibration& calibration,
                              std::uint64_t calibration_hash, const HybridOptions& options) {
    return std::move(
        calibrate_hybrid(session, calibration, calibration_hash, options, {options.model}).front());
}

namespace {

// The session's folder, checked against the options and the calibration.
SessionFolder hybrid_session(const fs::path& session, const StereoCalibration& calibration,
                             const HybridOptions& options, const std::vector<TableModel>& models) {
    options.validate();
    if (models.empty())
        throw std::invalid_argument("hybrid calibration: no table model asked for");
    SessionFolder folder = read_session_folder(
        session, std::nullopt, {Axis::x}, "hybrid calibration",
        "the hybrid model maps the projector column (vertical fringes) to X, Y, Z");
    if (calibration.sizes_known() && !(calibration.camera_size == folder.camera_size))
        throw InputError(folder.poses.front() / "capture.yaml", "camera",
                         "camera size " + size_text(folder.camera_size) +
                             " differs from the calibration's " +
                             size_text(calibration.camera_size));
    return folder;
}

} // namespace

std::vector<HybridResult>
calibrate_hybrid(const fs::path& session, const StereoCalibration& calibration,
                 std::uint64_t calibration_hash, const HybridOptions& options,
                 const std::vector<TableModel>& models, const std::vector<BoardView>& views) {
    const SessionFolder folder = hybrid_session(session, calibration, options, models);
    if (folder.board.kind != BoardDescription::Kind::checkerboard)
        throw InputError(
            folder.folder / "board.yaml", "kind",
            "the poses were seen as checkerboards, but the session's board is not one");
    if (views.size() != folder.poses.size())
        throw std::invalid_argument("hybrid calibration: " + std::to_string(views.size()) +
                                    " board views for the " + std::to_string(folder.poses.size()) +
                                    " poses of " + session.string());
    for (const BoardView& view : views)
        if (view.corners.found && !(view.bright_column.size() == folder.camera_size))
            throw std::invalid_argument("hybrid calibration: a board view's size differs from "
                                        "the session's camera");
    return detail::calibrate_hybrid_checkerboard(folder, calibration, calibration_hash, options,
                                                 models, &views);
}

std::vector<HybridResult> calibrate_hybrid(const fs::path& session,
                                           const StereoCalibration& calibration,
                                           std::uint64_t calibration_hash,
                                           const HybridOptions& options,
                                           const std::vector<TableModel>& models) {
    const SessionFolder folder = hybrid_session(session, calibration, options, models);
    const auto t_start = std::chrono::steady_clock::now();
    const auto say = [&](const std::string& s) {
        if (options.progress)
            options.progress(s);
    };
    if (folder.board.kind == BoardDescription::Kind::checkerboard)
        return detail::calibrate_hybrid_checkerboard(folder, calibration, calibration_hash, options,
                                                     models, nullptr);
    StereoCalibration calib = calibration;
    if (!calib.sizes_known()) {
        calib.camera_size = folder.camera_size;
        calib.projector_size = folder.projector_size;
    }
    const SvReconstructor sv(calib, options.sv);
    const Size camera = folder.camera_size;

    HybridResult common; // the poses, shared by every model's result
    common.trueness = calibration.trueness;
    common.board = BoardDescription::Kind::plane;
    std::vector<PoseSamples> samples;
    // Reading the next pose's PNG frames overlaps decoding and SV of this one.
    auto read_pose = [](const fs::path& f) { return read_capture_set(f); };
    std::future<CaptureSet> next = std::async(std::launch::async, read_pose, folder.poses.front());
    PointCloud cloud;
    for (std::size_t k = 0; k < folder.poses.size(); ++k) {
        const auto t0 = std::chrono::steady_clock::now();
        HybridPose pose;
        pose.folder = folder.poses[k];
        pose.name = pose.folder.filename().string();
        say("pose " + pose.name + " (" + std::to_string(k + 1) + "/" +
            std::to_string(folder.poses.size()) + ")");
        const CaptureSet capture = next.get();
        if (k + 1 < folder.poses.size())
            next = std::async(std::launch::async, read_pose, folder.poses[k + 1]);
        const DecodeResult decoded = decode(capture, options.decode); // InputError naming the field
        sv.reconstruct(decoded, ReconstructAxes::x, cloud);
        PlaneFitStats stats;
        BoardPlane plane;
        const bool fitted = fit_board_plane(cloud.xyz, options, plane, stats);
        pose.points = stats.points;
        pose.outliers = stats.outliers;
        const double coverage = double(stats.points) / double(camera.area());
        std::ostringstream why;
        why.precision(3);
        if (!fitted) {
            why << "no plane: " << stats.points << " points in a degenerate layout";
        } else if (coverage < options.min_pose_coverage) {
            why << "only " << 100 * coverage << " % of the camera pixels got a point (need "
                << 100 * options.min_pose_coverage << " %)";
        } else if (double(stats.outliers) > options.max_outlier_fraction * double(stats.points)) {
            why << "not planar: " << 100.0 * double(stats.outliers) / double(stats.points)
                << " % of the points are off the best plane (limit "
                << 100 * options.max_outlier_fraction << " %); something on the board?";
        }
        if (!why.str().empty()) {
            pose.skip_reason = why.str();
            say("  rejected " + pose.name + ": " + pose.skip_reason);
        } else {
            pose.usable = true;
            pose.plane = plane;
            pose.plane_rms_mm = stats.rms_mm;
            pose.plane_max_mm = stats.max_mm;
            pose.distance_mm = plane.d / plane.normal[2];
            pose.tilt_deg =
                std::acos(std::clamp(plane.normal[2], -1.0, 1.0)) * 180.0 / std::numbers::pi;
            PoseSamples s;
            s.phase = std::move(decoded.proj_x);
            smooth_phase(s.phase, options.phase_smoothing_radius,
                         ThreadPool::shared(options.threads));
            // Only pixels with an SV point on the plane give a sample (not
            // those of something standing on the board).
            s.sv_depth = Image<float>(camera);
            const float* xyz = cloud.xyz.data();
            for (std::size_t i = 0; i < camera.area(); ++i) {
                s.sv_depth.data()[i] = xyz[3 * i + 2]; // NaN for outliers and no point
                if (!std::isfinite(xyz[3 * i + 2]))
                    s.phase.data()[i] = kNaN;
            }
            s.plane = plane;
            samples.push_back(std::move(s));
        }
        pose.seconds = since(t0);
        common.poses.push_back(std::move(pose));
    }
    common.usable_poses = static_cast<int>(samples.size());
    common.seconds_poses = since(t_start);
    if (common.usable_poses < options.min_usable_poses)
        throw InputError(session, "",
                         std::to_string(common.usable_poses) + " usable plane poses of " +
                             std::to_string(common.poses.size()) + "; at least " +
                             std::to_string(options.min_usable_poses) + " are needed");

    // Every model is fitted from the same decoded, reconstructed poses.
    return detail::fit_hybrid_models(common, samples, sv.camera_rays(), folder.projector_size,
                                     calibration_hash, options, models, {});
}

namespace detail {

std::vector<HybridResult>
fit_hybrid_models(const HybridResult& common, const std::vector<PoseSamples>& samples,
                  const Image<float>& rays, Size projector, std::uint64_t calibration_hash,
                  const HybridOptions& options, const std::vector<TableModel>& models,
                  const ModelSampleSource& model_source) {
    const bool plane_session = common.board == BoardDescription::Kind::plane;
    std::vector<HybridResult> results;
    for (const TableModel model : models) {
        if (options.progress)
            options.progress(std::string("fitting the ") + to_string(model) + " model per pixel (" +
                             std::to_string(common.usable_poses) + " poses)");
        const auto t_fit = std::chrono::steady_clock::now();
        HybridResult result;
        result.poses = common.poses;
        result.usable_poses = common.usable_poses;
        result.seconds_poses = common.seconds_poses;
        result.time_split = common.time_split;
        result.board = common.board;
        result.samples = common.samples;
        result.trueness = common.trueness;
        TableInfo info;
        info.camera = rays.size();
        info.tile_width = options.tile_width;
        info.tile_height = options.tile_height;
        info.model = model;
        info.phase_axis = Axis::x;
        info.projector = projector;
        info.calibration_hash = calibration_hash;
        info.trueness = table_trueness(common.trueness);
        info.created_unix_s =
            static_cast<std::int64_t>(std::chrono::duration_cast<std::chrono::seconds>(
                                          std::chrono::system_clock::now().time_since_epoch())
                                          .count());
        PixelFitOptions fit;
        fit.model = model;
        fit.correction = plane_session && model == TableModel::polynomial
                             ? PlaneCorrection::perpendicular_foot
                             : PlaneCorrection::along_ray;
        fit.min_samples = options.min_poses;
        fit.max_condition = options.max_condition;
        fit.threads = options.threads;
        if (!plane_session && options.samples != HybridSamples::boards) {
            fit.min_samples = options.min_board_samples;
            // The rational model is exact for rays, as good beyond the boards'
            // depths as between them; a cubic in the column is not (60 mm each
            // side cost it 0.1 mm on the lens-defects rig): only between them.
            const double margin = options.depth_margin_mm(model);
            fit.model_samples = [&model_source, margin](int u, int v, double z_near, double z_far,
                                                        double* phase, double* depth,
                                                        int capacity) {
                return model_source(u, v, z_near - margin, z_far + margin, phase, depth, capacity);
            };
            fit.model_sample_count = options.model_samples;
            fit.board_weight = options.samples == HybridSamples::model ? 0.0 : 1.0;
        }
        PixelFit pixels = fit_pixel_models(samples, rays, info, fit);
        result.table = std::move(pixels.table);
        result.rms_x = std::move(pixels.rms_x);
        result.rms_y = std::move(pixels.rms_y);
        result.rms_z = std::move(pixels.rms_z);
        result.sigma_z = std::move(pixels.sigma_z);
        result.pose_count = std::move(pixels.samples);
        result.pixels_modelled = pixels.modelled;
        result.pixels_too_few_poses = pixels.too_few;
        result.pixels_ill_conditioned = pixels.ill_conditioned;
        result.seconds_fit = since(t_fit);
        result.time_split.add("per-pixel fits", result.seconds_fit);
        result.seconds_total = result.seconds_poses + result.seconds_fit;
        results.push_back(std::move(result));
    }
    return results;
}

} // namespace detail

} // namespace fpp::calib
