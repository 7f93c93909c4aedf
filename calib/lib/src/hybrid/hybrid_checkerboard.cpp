// The camera-anchored hybrid procedure: checkerboard poses placed by the
// camera alone, samples on their bright parts, the stereo model between
// them (see fpp/calib/hybrid_calibrate.hpp).

#include "fpp/calib/corners.hpp"
#include "fpp/calib/stereo_session.hpp"
#include "fpp/calib/time_split.hpp"
#include "fpp/error.hpp"
#include "hybrid_fit.hpp"
#include "phase_smoothing.hpp"
#include "session/pose_pipeline.hpp"
#include "stereo/bundle_adjustment.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <variant>

namespace fpp::calib::detail {

namespace fs = std::filesystem;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

double since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string fixed(double v, int digits) {
    std::ostringstream s;
    s.setf(std::ios::fixed);
    s.precision(digits);
    s << v;
    return s.str();
}

// The board's pose from its corners and the camera model alone: OpenCV's
// PnP on the undistorted rays, then the bundle adjustment of the pose with
// the camera held. Returns false when the corners cannot be undistorted or
// the solve fails; `rms` receives the reprojection RMS (px).
bool camera_pose(const StereoCalibration& calibration, const std::vector<Vec3>& board,
                 const std::vector<Vec2>& corners, RigidPose& pose, double& rms) {
    std::vector<cv::Point3d> object;
    std::vector<cv::Point2d> image;
    for (std::size_t k = 0; k < corners.size(); ++k) {
        Vec2 n{};
        if (!calibration.camera_ray(corners[k], n))
            return false;
        object.emplace_back(board[k][0], board[k][1], board[k][2]);
        image.emplace_back(n[0], n[1]);
    }
    cv::Mat rvec, tvec;
    try {
        if (!cv::solvePnP(object, image, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec))
            return false;
    } catch (const cv::Exception&) {
        return false;
    }
    RigState state;
    state.camera = calibration.camera;
    state.camera_grid = calibration.camera_correction;
    state.poses.push_back(
        {rotation_from_vector({rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2)}),
         {tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)}});
    std::vector<CornerObservation> observations;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (std::size_t k = 0; k < corners.size(); ++k)
        observations.push_back({0, board[k], corners[k], {nan, nan}});
    FreeParameters free;
    free.poses = free.camera_observations = true;
    try {
        const AdjustmentOutcome out =
            adjust(state, observations, {}, {true}, free, {}, 50, nullptr);
        rms = std::sqrt(out.data_cost / double(corners.size()));
    } catch (const std::runtime_error&) {
        return false;
    }
    pose = state.poses.front();
    return std::isfinite(rms);
}

// Whether (x, y) lies inside the convex quadrilateral q (in order).
bool inside_quad(const Vec2 q[4], double x, double y) {
    int sign = 0;
    for (int k = 0; k < 4; ++k) {
        const Vec2& a = q[k];
        const Vec2& b = q[(k + 1) % 4];
        const double c = (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
        const int s = c > 0 ? 1 : (c < 0 ? -1 : 0);
        if (s != 0) {
            if (sign != 0 && s != sign)
                return false;
            sign = s;
        }
    }
    return true;
}

// The decoded pixels inside the outer corners' quadrilateral, as a fraction
// of half its area (the white squares'; dark squares may not decode), at
// most 1.
double lit_fraction(const DecodeResult& decoded, const std::vector<Vec2>& corners, int columns,
                    int rows) {
    const Vec2 quad[4] = {corners[0], corners[std::size_t(columns - 1)],
                          corners[std::size_t(rows * columns - 1)],
                          corners[std::size_t((rows - 1) * columns)]};
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (const Vec2& q : quad) {
        x0 = std::min(x0, q[0]);
        x1 = std::max(x1, q[0]);
        y0 = std::min(y0, q[1]);
        y1 = std::max(y1, q[1]);
    }
    const Size size = decoded.proj_x.size();
    std::size_t inside = 0, lit = 0;
    for (int v = std::max(0, int(y0)); v <= std::min(size.height - 1, int(y1)); ++v)
        for (int u = std::max(0, int(x0)); u <= std::min(size.width - 1, int(x1)); ++u)
            if (inside_quad(quad, u, v)) {
                ++inside;
                lit += std::isfinite(decoded.proj_x.at(u, v)) ? 1 : 0;
            }
    return inside ? std::min(1.0, 2.0 * double(lit) / double(inside)) : 0.0;
}

// A pose's frames that the procedure uses. It needs the projector's column
// alone (the column, modulation and mean decode the same without the y
// blocks) and finds the board on the white frame; without a white frame it
// finds it on the mean of every phase frame, and then reads them all.
CaptureSet read_x_capture(const fs::path& folder) {
    const Sequence sequence = read_manifest(folder / "capture.yaml").sequence;
    const auto white = [](const PatternBlock& b) { return std::holds_alternative<WhiteBlock>(b); };
    if (std::none_of(sequence.begin(), sequence.end(), white))
        return read_capture_set(folder);
    return read_capture_set(folder, [](const PatternBlock& block) {
        return std::visit(
            [](const auto& b) {
                if constexpr (requires { b.axis; })
                    return b.axis != Axis::y;
                else
                    return true;
            },
            block);
    });
}

// What the poses share: the calibration, its SV reconstructor (and camera
// rays), the board and the options.
struct PoseContext {
    const StereoCalibration& calibration;
    const SvReconstructor& sv;
    const HybridOptions& options;
    const std::vector<Vec3>& board_points;
    Vec3 board_centre;
    int columns, rows;
    ThreadPool& pool;
};

// What processing a pose leaves: its entry in the result, its samples when
// it is usable, its progress lines and times (reported in pose order).
struct PoseOutcome {
    HybridPose pose;
    PoseSamples samples;
    std::vector<std::string> progress;
    TimeSplit time_split;
};

// A pose's view from its folder: read, decode, find the board.
BoardView read_board_view(const fs::path& folder, const PoseContext& context, TimeSplit& time) {
    StageTimer reading(time, "reading");
    const CaptureSet capture = read_x_capture(folder);
    reading.stop();
    StageTimer decoding(time, "decoding");
    const DecodeResult decoded =
        decode(capture, context.options.decode); // InputError naming the field
    decoding.stop();
    StageTimer corner_stage(time, "corners");
    const CheckerboardCorners corners =
        find_checkerboard(corner_textures(capture, decoded), context.columns, context.rows);
    corner_stage.stop();
    StageTimer bright(time, "bright parts");
    return observe_board(decoded, corners, context.columns, context.rows, context.options);
}

// One pose: its view (given, or read from its folder), then place the
// board, sample its bright parts, and compare the SV reconstruction of the
// samples with the camera's plane.
void process_pose(const fs::path& folder, const BoardView* given, const PoseContext& context,
                  PoseOutcome& outcome) {
    const auto t0 = std::chrono::steady_clock::now();
    const HybridOptions& options = context.options;
    const Image<float>& rays = context.sv.camera_rays();
    const Size camera = rays.size();
    TimeSplit& time = outcome.time_split;
    HybridPose& pose = outcome.pose;
    pose.folder = folder;
    pose.name = folder.filename() == "capture" ? folder.parent_path().filename().string()
                                               : folder.filename().string();
    const auto reject = [&](const std::string& why) {
        pose.skip_reason = why;
        outcome.progress.push_back("  rejected " + pose.name + ": " + why);
        pose.seconds = since(t0);
    };
    BoardView read;
    if (!given)
        read = read_board_view(folder, context, time);
    const BoardView& view = given ? *given : read;
    if (!view.corners.found)
        return reject("board not found: " + view.corners.failure);
    StageTimer placement(time, "board placement");
    RigidPose placed;
    if (!camera_pose(context.calibration, context.board_points, view.corners.points, placed,
                     pose.corner_rms_px))
        return reject("the camera model cannot place the board (its corners do not undistort or "
                      "the pose does not converge)");
    pose.lit_fraction = view.lit_fraction;
    if (pose.lit_fraction < options.min_lit_fraction)
        return reject("the projector lights only " + fixed(100 * pose.lit_fraction, 1) +
                      " % of the board's squares (need " +
                      fixed(100 * options.min_lit_fraction, 0) +
                      " %): the board is outside the projector's image or in its shadow");
    Vec3 normal{placed.R[2], placed.R[5], placed.R[8]};
    double d = normal[0] * placed.t[0] + normal[1] * placed.t[1] + normal[2] * placed.t[2];
    if (normal[2] < 0) {
        normal = {-normal[0], -normal[1], -normal[2]};
        d = -d;
    }
    pose.plane = {normal, d};
    pose.distance_mm = d / normal[2];
    pose.tilt_deg = std::acos(std::clamp(normal[2], -1.0, 1.0)) * 180.0 / std::numbers::pi;
    placement.stop();

    // Samples: the bright parts where the decoded column is the stereo
    // model's for the camera's plane (else not on the board), smoothed.
    StageTimer sampling(time, "samples");
    PoseSamples& s = outcome.samples;
    s.plane = pose.plane;
    s.phase = Image<float>(camera, 1, kNaN);
    context.pool.parallel_for(camera.height, 8, [&](int v0, int v1, int) {
        for (int v = v0; v < v1; ++v)
            for (int u = 0; u < camera.width; ++u) {
                const float p = view.bright_column.at(u, v);
                const double xn = rays.at(u, v, 0), yn = rays.at(u, v, 1);
                if (!std::isfinite(p) || !std::isfinite(xn))
                    continue;
                const double z = d / (normal[0] * xn + normal[1] * yn + normal[2]);
                const Vec2 q = context.calibration.projector_pixel({xn * z, yn * z, z});
                if (std::fabs(q[0] - double(p)) <= options.max_sample_deviation_px)
                    s.phase.at(u, v) = p;
            }
    });
    smooth_phase(s.phase, options.phase_smoothing_radius, context.pool);
    for (std::size_t i = 0; i < camera.area(); ++i)
        pose.samples += std::isfinite(s.phase.data()[i]) ? 1 : 0;
    sampling.stop();
    if (double(pose.samples) < 0.01 * double(camera.area()))
        return reject("only " + std::to_string(pose.samples) +
                      " pixels sample the board's bright parts (need 1 % of the image)");

    // The stereo model's view of the same board: its SV points on the
    // sampled pixels of every kSvStride-th row and column (a plane's
    // position and tilt need far fewer than a table's fit), against the
    // camera's plane.
    StageTimer sv_stage(time, "SV comparison (report)");
    constexpr int kSvStride = 8;
    Image<float> sv_points((camera.width + kSvStride - 1) / kSvStride,
                           (camera.height + kSvStride - 1) / kSvStride, 3, kNaN);
    double sum2 = 0;
    for (int v = 0; v < camera.height; v += kSvStride)
        for (int u = 0; u < camera.width; u += kSvStride) {
            Vec3 q{};
            if (!std::isfinite(s.phase.at(u, v)) ||
                !context.sv.triangulate_pixel_x(u, v, double(view.bright_column.at(u, v)), q))
                continue;
            const double dist = normal[0] * q[0] + normal[1] * q[1] + normal[2] * q[2] - d;
            sum2 += dist * dist;
            pose.plane_max_mm = std::max(pose.plane_max_mm, std::fabs(dist));
            ++pose.points;
            for (int c = 0; c < 3; ++c)
                sv_points.at(u / kSvStride, v / kSvStride, c) = float(q[std::size_t(c)]);
        }
    pose.plane_rms_mm = pose.points ? std::sqrt(sum2 / double(pose.points)) : 0;
    BoardPlane sv_plane;
    PlaneFitStats stats;
    if (fit_board_plane(sv_points, options, sv_plane, stats, false)) {
        const Vec3 rc = mul(placed.R, context.board_centre);
        const Vec3 centre{rc[0] + placed.t[0], rc[1] + placed.t[1], rc[2] + placed.t[2]};
        // > 0: SV's plane lies beyond the board's centre (seen from the camera).
        pose.sv_offset_mm =
            sv_plane.d - (sv_plane.normal[0] * centre[0] + sv_plane.normal[1] * centre[1] +
                          sv_plane.normal[2] * centre[2]);
        const double c = std::fabs(sv_plane.normal[0] * normal[0] + sv_plane.normal[1] * normal[1] +
                                   sv_plane.normal[2] * normal[2]);
        pose.sv_angle_deg = std::acos(std::min(1.0, c)) * 180.0 / std::numbers::pi;
    }
    pose.usable = true;
    pose.seconds = since(t0);
    outcome.progress.push_back(
        "  " + pose.name + ": board at " + fixed(pose.distance_mm, 1) + " mm, tilt " +
        fixed(pose.tilt_deg, 1) + " deg, corners " + fixed(pose.corner_rms_px, 4) + " px, " +
        std::to_string(pose.samples) + " samples; SV plane " + fixed(1000 * pose.sv_offset_mm, 1) +
        " um, " + fixed(pose.sv_angle_deg, 4) + " deg from the camera's");
}

} // namespace

std::vector<HybridResult> calibrate_hybrid_checkerboard(const SessionFolder& folder,
                                                        const StereoCalibration& calibration,
                                                        std::uint64_t calibration_hash,
                                                        const HybridOptions& options,
                                                        const std::vector<TableModel>& models,
                                                        const std::vector<BoardView>* views) {
    const auto t_start = std::chrono::steady_clock::now();
    const auto say = [&](const std::string& s) {
        if (options.progress)
            options.progress(s);
    };
    const fs::path board_file = folder.folder / "board.yaml";
    const BoardDescription& board = folder.board;
    if (!calibration.sizes_known())
        throw InputError(calibration.origin, "",
                         "a checkerboard session needs a calibration that knows its image sizes");
    if (!(calibration.projector_size == folder.projector_size))
        throw InputError(folder.poses.front() / "capture.yaml", "projector",
                         "projector size differs from the calibration's");
    if (calibration.board_square_size > 0 &&
        std::fabs(board.square_size / calibration.board_square_size - 1) >
            options.square_size_tolerance)
        throw InputError(board_file, "square_size",
                         fixed(board.square_size, 4) + " mm differs from the " +
                             fixed(calibration.board_square_size, 4) +
                             " mm of the board the stereo calibration was made with: the camera "
                             "would place every board at the wrong depth");
    const SvReconstructor sv(calibration, options.sv);
    const Image<float>& rays = sv.camera_rays();
    const int columns = board.inner_columns, rows = board.inner_rows;
    const std::vector<Vec3> board_points = checkerboard_points(columns, rows, board.square_size);
    const Vec3 board_centre{(columns - 1) * 0.5 * board.square_size,
                            (rows - 1) * 0.5 * board.square_size, 0};
    const Size projector = calibration.projector_size;
    const auto on_projector = [&](const Vec2& p) {
        return p[0] >= -0.5 && p[0] <= projector.width - 0.5 && p[1] >= -0.5 &&
               p[1] <= projector.height - 0.5;
    };
    ThreadPool& pool = ThreadPool::shared(options.threads);

    HybridResult common;
    common.trueness = calibration.trueness;
    common.board = BoardDescription::Kind::checkerboard;
    common.samples = options.samples;
    // Each pose on its own thread (poses rather than pixels in parallel:
    // reading and finding the board are sequential per pose); lines and
    // results in pose order.
    const PoseContext context{calibration,  sv,      options, board_points,
                              board_centre, columns, rows,    pool};
    std::vector<PoseOutcome> outcomes(folder.poses.size());
    std::vector<PoseSamples> samples;
    for_each_pose(
        pool, static_cast<int>(folder.poses.size()),
        [&](int k, int) {
            process_pose(folder.poses[std::size_t(k)], views ? &(*views)[std::size_t(k)] : nullptr,
                         context, outcomes[std::size_t(k)]);
        },
        [&](int k) {
            PoseOutcome& o = outcomes[std::size_t(k)];
            say("pose " + o.pose.name + " (" + std::to_string(k + 1) + "/" +
                std::to_string(folder.poses.size()) + ")");
            for (const std::string& line : o.progress)
                say(line);
            common.time_split.add(o.time_split);
            if (o.pose.usable)
                samples.push_back(std::move(o.samples));
            common.poses.push_back(std::move(o.pose));
        });
    common.usable_poses = static_cast<int>(samples.size());
    common.seconds_poses = since(t_start);
    if (common.usable_poses < options.min_usable_poses) {
        std::string reasons;
        for (const HybridPose& p : common.poses)
            if (!p.usable)
                reasons += "\n  " + p.name + ": " + p.skip_reason;
        throw InputError(folder.folder, "",
                         std::to_string(common.usable_poses) + " usable checkerboard poses of " +
                             std::to_string(common.poses.size()) + "; at least " +
                             std::to_string(options.min_usable_poses) + " are needed" + reasons);
    }

    // The stereo model along a pixel's ray, over the depths asked for.
    const int count = options.model_samples;
    const ModelSampleSource model = [&](int u, int v, double z0, double z1, double* phase,
                                        double* depth, int capacity) {
        const double xn = rays.at(u, v, 0), yn = rays.at(u, v, 1);
        int n = 0;
        for (int k = 0; k < std::min(count, capacity); ++k) {
            const double z = z0 + (z1 - z0) * k / (count - 1);
            const Vec2 q = calibration.projector_pixel({xn * z, yn * z, z});
            if (!on_projector(q))
                continue;
            phase[n] = q[0];
            depth[n] = z;
            ++n;
        }
        return n;
    };
    return fit_hybrid_models(common, samples, rays, projector, calibration_hash, options, models,
                             model);
}

} // namespace fpp::calib::detail

namespace fpp::calib {

namespace fs = std::filesystem;

BoardView observe_board(const DecodeResult& decoded, const CheckerboardCorners& corners,
                        int columns, int rows, const HybridOptions& options) {
    BoardView view;
    view.corners = corners;
    if (!corners.found)
        return view;
    view.lit_fraction = detail::lit_fraction(decoded, corners.points, columns, rows);
    const Image<std::uint8_t> bright = bright_board_mask(decoded, false, options.bright);
    view.bright_column = Image<float>(decoded.proj_x.size(), 1, detail::kNaN);
    const std::size_t n = bright.pixel_count();
    for (std::size_t i = 0; i < n; ++i)
        if (bright.data()[i])
            view.bright_column.data()[i] = decoded.proj_x.data()[i];
    return view;
}

void keep_board_views(const fs::path& session, const HybridOptions& hybrid,
                      StereoSessionOptions& stereo, std::vector<BoardView>& views) {
    const SessionFolder folder = read_session_folder(
        session, BoardDescription::Kind::checkerboard, {Axis::x, Axis::y},
        "calibration from one session",
        "the stereo calibration needs the projector's x and y coordinate of every corner (phase "
        "in both directions)");
    const int columns = folder.board.inner_columns, rows = folder.board.inner_rows;
    views.assign(folder.poses.size(), BoardView{});
    // Each pose writes its own element, from the thread processing it.
    stereo.on_pose = [&views, &hybrid, columns, rows](int pose, const DecodeResult& decoded,
                                                      const CheckerboardCorners& corners) {
        views.at(std::size_t(pose)) = observe_board(decoded, corners, columns, rows, hybrid);
    };
}

} // namespace fpp::calib
