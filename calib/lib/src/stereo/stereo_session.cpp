// Stereo calibration of a session folder: validation, per-pose decoding and
// corners, calibration.

#include "fpp/calib/stereo_session.hpp"

#include "fpp/calib/session_folder.hpp"
#include "fpp/calib/time_split.hpp"
#include "session/pose_pipeline.hpp"

#include "fpp/error.hpp"
#include "fpp/image_io.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <sstream>
#include <variant>

namespace fpp::calib {

namespace fs = std::filesystem;

namespace {

double since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Image<std::uint8_t> to_8bit_view(const Image<float>& image) {
    std::vector<float> values;
    const std::size_t n = image.pixel_count();
    const std::size_t stride = std::max<std::size_t>(1, n / 100000);
    for (std::size_t i = 0; i < n; i += stride)
        if (std::isfinite(image.data()[i]))
            values.push_back(image.data()[i]);
    float lo = 0, hi = 255;
    if (!values.empty()) {
        std::sort(values.begin(), values.end());
        lo = values[values.size() / 200];
        hi = values[values.size() - 1 - values.size() / 200];
    }
    if (!(hi > lo))
        hi = lo + 1;
    Image<std::uint8_t> out(image.size());
    for (std::size_t i = 0; i < n; ++i) {
        const float v = image.data()[i];
        const float s = std::isfinite(v) ? (v - lo) * 255.0f / (hi - lo) : 0.0f;
        out.data()[i] = static_cast<std::uint8_t>(std::clamp(s, 0.0f, 255.0f) + 0.5f);
    }
    return out;
}

// What processing a pose leaves besides its SessionPose: its progress
// lines and times, reported in pose order.
struct PoseOutcome {
    std::vector<std::string> progress;
    TimeSplit time_split;
};

struct PoseContext {
    const StereoSessionOptions& options;
    int columns, rows;
    bool dense;
    int dense_step;
};

// One pose: decode, corners, their projector coordinates (by every method
// and against the truth for simulated captures, on request), dense samples.
void process_pose(int index, const fs::path& folder, const PoseContext& context, SessionPose& pose,
                  PoseObservations& observations, PoseOutcome& outcome) {
    const StereoSessionOptions& options = context.options;
    const int columns = context.columns, rows = context.rows;
    TimeSplit& time = outcome.time_split;
    pose.folder = folder;
    pose.name = folder.filename().string();
    StageTimer reading(time, "reading");
    const CaptureSet capture = read_capture_set(folder);
    reading.stop();
    StageTimer decoding(time, "decoding");
    const DecodeResult decoded = decode(capture, options.decode); // InputError naming the field
    pose.decode_seconds = decoding.stop();

    StageTimer corners(time, "corners");
    const std::vector<CornerTexture> textures = corner_textures(capture, decoded);
    pose.corners = find_checkerboard(textures, columns, rows, options.finder);
    if (!textures.empty()) {
        const CornerTexture* used = &textures.front();
        for (const CornerTexture& t : textures)
            if (t.source == pose.corners.texture)
                used = &t;
        pose.texture = to_8bit_view(used->image);
    }
    pose.corner_seconds = corners.stop();
    if (options.on_pose)
        options.on_pose(index, decoded, pose.corners);
    if (!pose.corners.found) {
        pose.skip_reason = pose.corners.failure;
        outcome.progress.push_back("  skipped " + pose.name + ": " + pose.skip_reason);
        return;
    }
    if (context.dense) {
        StageTimer dense_samples(time, "dense samples");
        dense_projector_samples(decoded, bright_board_mask(decoded, true, options.bright),
                                context.dense_step, observations.dense_camera,
                                observations.dense_projector);
    }
    // The other methods only for the report's comparison with the
    // simulator's truth (about 0.16 s a pose at full size).
    const bool compare = options.compare_corner_methods && capture.manifest.truth &&
                         !capture.manifest.truth->projector.empty();
    for (int m = 0; m < kCornerMethods; ++m) {
        ProjectorCornerOptions o = options.corners;
        o.method = static_cast<CornerMethod>(m);
        if (o.method != options.corners.method && !compare)
            continue;
        StageTimer projector(time, o.method == options.corners.method
                                       ? "projector corners"
                                       : "projector corners of the other methods (report)");
        pose.projector[static_cast<std::size_t>(m)] = projector_corners(
            decoded, pose.corners.points, columns, rows, pose.corners.origin_square_black, o);
        pose.corner_seconds += projector.stop();
    }

    // Ground truth of simulated captures: each method against truth_proj.
    if (compare) {
        StageTimer truth_comparison(time, "ground truth (report)");
        const Image<float> truth = read_tiff_float(folder / capture.manifest.truth->projector);
        for (int m = 0; m < kCornerMethods; ++m) {
            double sum = 0;
            int count = 0;
            const ProjectorCorners& pc = pose.projector[static_cast<std::size_t>(m)];
            for (std::size_t k = 0; k < pose.corners.points.size(); ++k) {
                const Vec2& c = pose.corners.points[k];
                const double tx = sample_bilinear(truth, c[0], c[1], 0);
                const double ty = sample_bilinear(truth, c[0], c[1], 1);
                if (!pc.valid[k] || !std::isfinite(tx) || !std::isfinite(ty))
                    continue;
                sum += std::pow(pc.points[k][0] - tx, 2) + std::pow(pc.points[k][1] - ty, 2);
                ++count;
            }
            pose.truth_rms[static_cast<std::size_t>(m)] = count ? std::sqrt(sum / count) : -1;
            pose.truth_points = count;
        }
    }

    const ProjectorCorners& chosen =
        pose.projector[static_cast<std::size_t>(options.corners.method)];
    const int valid = static_cast<int>(chosen.valid.size()) - chosen.failed;
    std::ostringstream msg;
    msg << "  " << pose.name << ": board found (" << pose.corners.finder << " finder on "
        << pose.corners.texture << "), projector coordinates for " << valid << "/"
        << chosen.valid.size() << " corners";
    outcome.progress.push_back(msg.str());
    if (valid < options.min_projector_corner_fraction * static_cast<double>(chosen.valid.size()) ||
        valid < 6) {
        pose.skip_reason = "projector coordinates for only " + std::to_string(valid) + " of " +
                           std::to_string(chosen.valid.size()) +
                           " corners (phase invalid around the board)";
        outcome.progress.push_back("  skipped " + pose.name + ": " + pose.skip_reason);
    } else {
        pose.usable = true;
    }
}

// calibrate_session's last stages.

// The usable poses' observations in result.observations (result.calibrated:
// their indices in result.poses); a session with fewer than 3 is refused,
// naming why each pose was skipped.
void keep_usable_poses(const fs::path& session, const std::vector<Vec3>& board_points,
                       std::vector<PoseObservations>& per_pose, SessionResult& result) {
    std::string skipped;
    std::vector<PoseObservations> used_observations;
    for (std::size_t p = 0; p < result.poses.size(); ++p) {
        const SessionPose& pose = result.poses[p];
        if (!pose.usable) {
            skipped += "\n  " + pose.name + ": " + pose.skip_reason;
            continue;
        }
        PoseObservations& o = per_pose[p];
        o.name = pose.name;
        o.board = board_points;
        o.camera = pose.corners.points;
        o.projector = pose.projector[static_cast<std::size_t>(result.method)].points;
        used_observations.push_back(std::move(o));
        result.calibrated.push_back(static_cast<int>(p));
    }
    result.observations = std::move(used_observations);
    const std::vector<PoseObservations>& observations = result.observations;
    if (observations.size() < 3)
        throw TooFewPosesError(
            session, "only " + std::to_string(observations.size()) + " of " +
                         std::to_string(result.poses.size()) +
                         " poses are usable; stereo calibration needs at least 3" + skipped);
}

// The stereo calibration of the kept poses, and with options.compare_skew
// the other skew setting's alongside (for the report).
void calibrate_kept_poses(const StereoSessionOptions& options, SessionResult& result) {
    const auto say = [&](const std::string& s) {
        if (options.progress)
            options.progress(s);
    };
    const std::vector<PoseObservations>& observations = result.observations;
    const auto t_cal = std::chrono::steady_clock::now();
    StereoOptions stereo = options.stereo;
    stereo.progress = options.progress;
    say("calibrating from " + std::to_string(observations.size()) + " poses");
    StageTimer initialisation(result.time_split, "OpenCV initialisation");
    const StereoStart start = initialise_stereo(observations, result.camera_size,
                                                result.projector_size, options.progress);
    initialisation.stop();
    // The other skew setting's calibration (for the report) on its own
    // thread meanwhile, from the same start: the two share no other state.
    std::future<StereoResult> other_skew;
    if (options.compare_skew) {
        StereoOptions other = stereo;
        other.skew = !stereo.skew;
        other.progress = nullptr;
        say(std::string("for comparison, alongside: calibrating with skew ") +
            (other.skew ? "estimated" : "fixed at 0"));
        other_skew =
            std::async(std::launch::async, [&observations, &start, camera = result.camera_size,
                                            projector = result.projector_size, other] {
                return stereo_calibrate(observations, camera, projector, other, start);
            });
    }
    result.stereo =
        stereo_calibrate(observations, result.camera_size, result.projector_size, stereo, start);
    result.time_split.add(result.stereo.time_split);
    if (other_skew.valid()) {
        StageTimer waiting(result.time_split, "waiting for the other skew's calibration");
        result.other_skew = other_skew.get();
        waiting.stop();
        for (const auto& [stage, seconds] : result.other_skew->time_split.stages())
            result.time_split.add(stage + " (other skew, report)", seconds);
    }
    result.seconds_calibration = since(t_cal);
}

} // namespace

std::vector<Vec3> checkerboard_points(int columns, int rows, double square_size) {
    std::vector<Vec3> points;
    points.reserve(static_cast<std::size_t>(columns * rows));
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < columns; ++i)
            points.push_back({i * square_size, j * square_size, 0.0});
    return points;
}

SessionResult calibrate_session(const fs::path& session, const StereoSessionOptions& options) {
    const auto t_start = std::chrono::steady_clock::now();
    const auto say = [&](const std::string& s) {
        if (options.progress)
            options.progress(s);
    };
    SessionResult result;
    result.folder = session;
    result.method = options.corners.method;
    // Every manifest first: sizes and axes are checked before any decoding.
    const SessionFolder folder = read_session_folder(
        session, BoardDescription::Kind::checkerboard, {Axis::x, Axis::y}, "stereo calibration",
        "stereo calibration needs the projector's x and y coordinate of every corner (phase in "
        "both directions)");
    result.board = folder.board;
    result.camera_size = folder.camera_size;
    result.projector_size = folder.projector_size;
    const int columns = result.board.inner_columns, rows = result.board.inner_rows;
    const std::vector<fs::path>& folders = folder.poses;

    const std::vector<Vec3> board_points =
        checkerboard_points(columns, rows, result.board.square_size);
    const bool dense =
        options.dense_samples && options.stereo.procedure == StereoProcedure::camera_first;
    const int dense_step =
        options.dense_step_px > 0
            ? options.dense_step_px
            : std::max(2, static_cast<int>(
                              std::lround(std::sqrt(double(result.camera_size.area()) / 8000.0))));
    // Each pose on its own thread, decoded there (poses rather than pixels
    // in parallel: reading, corners and their projector coordinates are
    // sequential per pose); lines and results in pose order.
    std::vector<PoseObservations> per_pose(folders.size());
    std::vector<PoseOutcome> outcomes(folders.size());
    result.poses.resize(folders.size());
    PoseContext context{options, columns, rows, dense, dense_step};
    detail::for_each_pose(
        ThreadPool::shared(options.decode.threads), static_cast<int>(folders.size()),
        [&](int p, int) {
            process_pose(p, folders[std::size_t(p)], context, result.poses[std::size_t(p)],
                         per_pose[std::size_t(p)], outcomes[std::size_t(p)]);
        },
        [&](int p) {
            const PoseOutcome& o = outcomes[std::size_t(p)];
            say("pose " + result.poses[std::size_t(p)].name + " (" + std::to_string(p + 1) + "/" +
                std::to_string(folders.size()) + ")");
            for (const std::string& line : o.progress)
                say(line);
            result.time_split.add(o.time_split);
            result.seconds_decode += result.poses[std::size_t(p)].decode_seconds;
            result.seconds_corners += result.poses[std::size_t(p)].corner_seconds;
        });

    keep_usable_poses(session, board_points, per_pose, result);
    calibrate_kept_poses(options, result);
    result.stereo.calibration.origin = "fpp-calib stereo " + session.string();
    result.stereo.calibration.board_square_size = result.board.square_size;
    result.seconds_total = since(t_start);
    return result;
}

} // namespace fpp::calib
