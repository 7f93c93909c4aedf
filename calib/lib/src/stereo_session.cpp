// Stereo calibration of a session folder: validation, per-pose decoding and
// corners, calibration.

#include "fpp/calib/stereo_session.hpp"

#include "fpp/calib/session_folder.hpp"
#include "fpp/calib/time_split.hpp"

#include "fpp/error.hpp"
#include "fpp/image_io.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
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
    const bool dense = options.dense_samples &&
                       options.stereo.procedure == StereoProcedure::camera_first;
    const int dense_step =
        options.dense_step_px > 0
            ? options.dense_step_px
            : std::max(2, static_cast<int>(std::lround(
                              std::sqrt(double(result.camera_size.area()) / 8000.0))));
    std::vector<PoseObservations> per_pose(folders.size());
    for (std::size_t p = 0; p < folders.size(); ++p) {
        SessionPose pose;
        pose.folder = folders[p];
        pose.name = folders[p].filename().string();
        say("pose " + pose.name + " (" + std::to_string(p + 1) + "/" +
            std::to_string(folders.size()) + "): decoding");
        StageTimer reading(result.time_split, "reading");
        const CaptureSet capture = read_capture_set(folders[p]);
        reading.stop();
        auto t0 = std::chrono::steady_clock::now();
        DecodeResult decoded;
        try {
            StageTimer decoding(result.time_split, "decoding");
            decoded = decode(capture, options.decode);
        } catch (const std::invalid_argument& e) {
            throw InputError(folders[p] / "capture.yaml", "sequence",
                             std::string("cannot be decoded: ") + e.what());
        }
        pose.decode_seconds = since(t0);
        result.seconds_decode += pose.decode_seconds;

        t0 = std::chrono::steady_clock::now();
        StageTimer corners(result.time_split, "corners");
        const std::vector<CornerTexture> textures = corner_textures(capture, decoded);
        pose.corners = find_checkerboard(textures, columns, rows, options.finder);
        if (!textures.empty()) {
            const CornerTexture* used = &textures.front();
            for (const CornerTexture& t : textures)
                if (t.source == pose.corners.texture)
                    used = &t;
            pose.texture = to_8bit_view(used->image);
        }
        if (!pose.corners.found) {
            pose.skip_reason = pose.corners.failure;
            say("  skipped " + pose.name + ": " + pose.skip_reason);
            pose.corner_seconds = since(t0);
            result.seconds_corners += pose.corner_seconds;
            result.poses.push_back(std::move(pose));
            continue;
        }
        corners.stop();
        if (dense) {
            StageTimer dense_samples(result.time_split, "dense samples");
            dense_projector_samples(decoded, bright_board_mask(decoded, true, options.bright),
                                    dense_step, per_pose[p].dense_camera,
                                    per_pose[p].dense_projector);
        }
        for (int m = 0; m < kCornerMethods; ++m) {
            ProjectorCornerOptions o = options.corners;
            o.method = static_cast<CornerMethod>(m);
            StageTimer projector(result.time_split,
                                 o.method == options.corners.method
                                     ? "projector corners"
                                     : "projector corners of the other methods (report)");
            pose.projector[static_cast<std::size_t>(m)] = projector_corners(
                decoded, pose.corners.points, columns, rows, pose.corners.origin_square_black, o);
        }
        pose.corner_seconds = since(t0);
        result.seconds_corners += pose.corner_seconds;

        // Ground truth of simulated captures: each method against truth_proj.
        StageTimer truth_comparison(result.time_split, "ground truth (report)");
        if (capture.manifest.truth && !capture.manifest.truth->projector.empty()) {
            const Image<float> truth =
                read_tiff_float(folders[p] / capture.manifest.truth->projector);
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

        const ProjectorCorners& chosen = pose.projector[static_cast<std::size_t>(result.method)];
        const int valid = static_cast<int>(chosen.valid.size()) - chosen.failed;
        std::ostringstream msg;
        msg << "  " << pose.name << ": board found (" << pose.corners.finder << " finder on "
            << pose.corners.texture << "), projector coordinates for " << valid << "/"
            << chosen.valid.size() << " corners";
        say(msg.str());
        if (valid <
                options.min_projector_corner_fraction * static_cast<double>(chosen.valid.size()) ||
            valid < 6) {
            pose.skip_reason = "projector coordinates for only " + std::to_string(valid) + " of " +
                               std::to_string(chosen.valid.size()) +
                               " corners (phase invalid around the board)";
            say("  skipped " + pose.name + ": " + pose.skip_reason);
        } else {
            pose.usable = true;
        }
        result.poses.push_back(std::move(pose));
    }

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
        throw InputError(session, "",
                         "only " + std::to_string(observations.size()) + " of " +
                             std::to_string(result.poses.size()) +
                             " poses are usable; stereo calibration needs at least 3" + skipped);

    const auto t_cal = std::chrono::steady_clock::now();
    StereoOptions stereo = options.stereo;
    stereo.progress = options.progress;
    say("calibrating from " + std::to_string(observations.size()) + " poses");
    result.stereo =
        stereo_calibrate(observations, result.camera_size, result.projector_size, stereo);
    result.time_split.add(result.stereo.time_split);
    if (options.compare_skew) {
        StageTimer other_skew(result.time_split, "calibration with the other skew (report)");
        StereoOptions other = stereo;
        other.skew = !stereo.skew;
        other.progress = nullptr;
        say(std::string("for comparison: calibrating with skew ") +
            (other.skew ? "estimated" : "fixed at 0"));
        result.other_skew =
            stereo_calibrate(observations, result.camera_size, result.projector_size, other);
    }
    result.seconds_calibration = since(t_cal);
    result.stereo.calibration.origin = "fpp-calib stereo " + session.string();
    result.stereo.calibration.board_square_size = result.board.square_size;
    result.seconds_total = since(t_start);
    return result;
}

} // namespace fpp::calib
