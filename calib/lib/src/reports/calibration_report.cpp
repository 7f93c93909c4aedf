// Report of a stereo calibration: Markdown summary and PNG figures.

#include "fpp/calib/calibration_report.hpp"

#include "fpp/calib/plots.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace fpp::calib {

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string fmt(double v, int digits) {
    if (!std::isfinite(v) || v < -1e300)
        return "-";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", digits, v);
    return buf;
}

std::string fmt_g(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

cv::Scalar pose_colour(int index, int count) {
    cv::Mat hsv(1, 1, CV_8UC3,
                cv::Scalar(static_cast<double>(180 * index / std::max(count, 1)), 220, 230));
    cv::Mat bgr;
    cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
    const cv::Vec3b c = bgr.at<cv::Vec3b>(0, 0);
    return cv::Scalar(c[0], c[1], c[2]);
}

cv::Point2f to_point(const Vec2& p, double scale) {
    return {static_cast<float>((p[0] + 0.5) * scale - 0.5),
            static_cast<float>((p[1] + 0.5) * scale - 0.5)};
}

// The texture with the corners (green where `method` gave their projector
// coordinates), the origin and the board axes.
cv::Mat corner_figure(const SessionPose& pose, CornerMethod method, int columns, int rows) {
    const Image<std::uint8_t>& t = pose.texture;
    if (t.empty())
        return {};
    const cv::Mat grey(t.height(), t.width(), CV_8U, const_cast<std::uint8_t*>(t.data()));
    const double scale = std::min(1.0, 1000.0 / t.width());
    cv::Mat small;
    cv::resize(grey, small, cv::Size(), scale, scale, cv::INTER_AREA);
    cv::Mat out;
    cv::cvtColor(small, out, cv::COLOR_GRAY2BGR);
    if (!pose.corners.found) {
        cv::putText(out, "board not found", {20, 40}, cv::FONT_HERSHEY_SIMPLEX, 1.0, {0, 0, 255},
                    2);
        return out;
    }
    const auto& p = pose.corners.points;
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < columns; ++i) {
            const std::size_t k = static_cast<std::size_t>(j * columns + i);
            if (i + 1 < columns)
                cv::line(out, to_point(p[k], scale), to_point(p[k + 1], scale), {0, 200, 255}, 1,
                         cv::LINE_AA);
            if (j + 1 < rows)
                cv::line(out, to_point(p[k], scale),
                         to_point(p[k + static_cast<std::size_t>(columns)], scale), {0, 200, 255},
                         1, cv::LINE_AA);
            const ProjectorCorners& used = pose.projector[static_cast<std::size_t>(method)];
            const bool projected = used.valid.size() == p.size() && used.valid[k];
            cv::circle(out, to_point(p[k], scale), 3,
                       projected ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 0, 255), 1, cv::LINE_AA);
        }
    cv::arrowedLine(out, to_point(p[0], scale), to_point(p[1], scale), {0, 0, 255}, 2, cv::LINE_AA,
                    0, 0.3);
    cv::arrowedLine(out, to_point(p[0], scale),
                    to_point(p[static_cast<std::size_t>(columns)], scale), {0, 200, 0}, 2,
                    cv::LINE_AA, 0, 0.3);
    cv::circle(out, to_point(p[0], scale), 7, {0, 0, 255}, 2, cv::LINE_AA);
    cv::putText(out, pose.name + ": " + pose.corners.finder + " finder", {10, 25},
                cv::FONT_HERSHEY_SIMPLEX, 0.7, {0, 255, 255}, 2);
    return out;
}

// Residual vectors of one device, magnified, on a canvas of its image size.
cv::Mat residual_figure(const SessionResult& r, bool projector) {
    const Size size = projector ? r.projector_size : r.camera_size;
    const double scale = std::min(1.0, 1000.0 / size.width);
    cv::Mat out(static_cast<int>(size.height * scale) + 40, static_cast<int>(size.width * scale),
                CV_8UC3, cv::Scalar(40, 40, 40));
    const StereoResult& s = r.stereo;
    const int poses = static_cast<int>(r.calibrated.size());
    // Gain: the 95th percentile residual becomes 4 % of the canvas width.
    std::vector<double> mags;
    for (int n = 0; n < poses; ++n) {
        const auto& res = projector ? s.projector_residuals[static_cast<std::size_t>(n)]
                                    : s.camera_residuals[static_cast<std::size_t>(n)];
        for (const Vec2& e : res)
            if (std::isfinite(e[0]))
                mags.push_back(std::hypot(e[0], e[1]));
    }
    std::sort(mags.begin(), mags.end());
    const double p95 = mags.empty() ? 1 : std::max(1e-6, mags[mags.size() * 95 / 100]);
    double gain = 0.04 * size.width / p95;
    const double nice[] = {1, 2, 5};
    double rounded = 1;
    for (double decade = 1; decade < 1e7; decade *= 10)
        for (double m : nice)
            if (m * decade <= gain)
                rounded = m * decade;
    gain = rounded;
    for (int n = 0; n < poses; ++n) {
        const SessionPose& pose =
            r.poses[static_cast<std::size_t>(r.calibrated[static_cast<std::size_t>(n)])];
        const auto& res = projector ? s.projector_residuals[static_cast<std::size_t>(n)]
                                    : s.camera_residuals[static_cast<std::size_t>(n)];
        const auto& at = projector ? pose.projector[static_cast<std::size_t>(r.method)].points
                                   : pose.corners.points;
        const cv::Scalar colour = pose_colour(n, poses);
        for (std::size_t k = 0; k < res.size() && k < at.size(); ++k) {
            if (!std::isfinite(res[k][0]) || !std::isfinite(at[k][0]))
                continue;
            const cv::Point2f a = to_point(at[k], scale);
            const cv::Point2f b(a.x + static_cast<float>(res[k][0] * gain * scale),
                                a.y + static_cast<float>(res[k][1] * gain * scale));
            cv::circle(out, a, 1, colour, -1);
            cv::line(out, a, b, colour, 1, cv::LINE_AA);
        }
    }
    const std::string label =
        std::string(projector ? "projector" : "camera") +
        " reprojection residuals (predicted - measured) x" + fmt(gain, 0) + ", RMS " +
        fmt(projector ? s.calibration.projector_rms : s.calibration.camera_rms, 3) + " px";
    cv::putText(out, label, {10, out.rows - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.55, {255, 255, 255}, 1,
                cv::LINE_AA);
    return out;
}

cv::Mat rms_figure(const SessionResult& r) {
    const auto& poses = r.stereo.calibration.poses;
    const int n = static_cast<int>(poses.size());
    const int width = std::max(400, 60 * n + 100), height = 360, left = 60, bottom = 60, top = 40;
    cv::Mat out(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    double vmax = 1e-6;
    for (const PoseResidual& p : poses)
        vmax = std::max({vmax, p.camera_rms, p.projector_rms});
    vmax *= 1.15;
    const int plot_h = height - bottom - top;
    auto y_of = [&](double v) { return static_cast<int>(height - bottom - v / vmax * plot_h); };
    cv::line(out, {left, height - bottom}, {width - 20, height - bottom}, {0, 0, 0}, 1);
    cv::line(out, {left, top}, {left, height - bottom}, {0, 0, 0}, 1);
    for (int t = 0; t <= 4; ++t) {
        const double v = vmax * t / 4;
        cv::line(out, {left - 4, y_of(v)}, {left, y_of(v)}, {0, 0, 0}, 1);
        cv::putText(out, fmt(v, 3), {2, y_of(v) + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.35, {0, 0, 0}, 1,
                    cv::LINE_AA);
    }
    for (int i = 0; i < n; ++i) {
        const PoseResidual& p = poses[static_cast<std::size_t>(i)];
        const int x = left + 20 + 60 * i;
        const cv::Scalar cam(200, 120, 40), proj(40, 120, 230);
        cv::rectangle(out, {x, y_of(p.camera_rms)}, {x + 20, height - bottom}, cam, cv::FILLED);
        cv::rectangle(out, {x + 22, y_of(p.projector_rms)}, {x + 42, height - bottom}, proj,
                      cv::FILLED);
        if (!p.used || !p.note.empty())
            cv::putText(out, p.used ? "!" : "x", {x + 16, top - 5}, cv::FONT_HERSHEY_SIMPLEX, 0.6,
                        {0, 0, 255}, 2);
        std::string label = p.name;
        if (label.size() > 8)
            label = label.substr(label.size() - 8);
        cv::putText(out, label, {x - 4, height - bottom + 18}, cv::FONT_HERSHEY_SIMPLEX, 0.35,
                    {0, 0, 0}, 1, cv::LINE_AA);
    }
    cv::putText(out, "per-pose RMS (px): camera (blue), projector (orange); ! outlier, x dropped",
                {left, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1, cv::LINE_AA);
    return out;
}

std::string lens_rows(const LensModel& c, const LensModel& cs, const LensModel& p,
                      const LensModel& ps) {
    struct Row {
        const char* name;
        double LensModel::*field;
        int digits;
    };
    const Row rows[] = {{"fu (px)", &LensModel::fu, 2},     {"fv (px)", &LensModel::fv, 2},
                        {"cu (px)", &LensModel::cu, 2},     {"cv (px)", &LensModel::cv, 2},
                        {"skew (px)", &LensModel::skew, 3}, {"k1", &LensModel::k1, 5},
                        {"k2", &LensModel::k2, 5},          {"k3", &LensModel::k3, 4},
                        {"p1", &LensModel::p1, 6},          {"p2", &LensModel::p2, 6}};
    std::string s =
        "| parameter | camera | ± 1 sigma | projector | ± 1 sigma |\n|---|---:|---:|---:|---:|\n";
    for (const Row& r : rows)
        s += std::string("| ") + r.name + " | " + fmt(c.*r.field, r.digits) + " | " +
             fmt_g(cs.*r.field) + " | " + fmt(p.*r.field, r.digits) + " | " + fmt_g(ps.*r.field) +
             " |\n";
    return s;
}

} // namespace

Vec3 euler_deg_from_rotation(const Mat3& R) {
    const double b = -std::asin(std::clamp(R[6], -1.0, 1.0));
    const double a = std::atan2(R[7], R[8]);
    const double c = std::atan2(R[3], R[0]);
    return {a * 180 / kPi, b * 180 / kPi, c * 180 / kPi};
}

namespace {

// summary.md's sections, in order.

void session_section(std::ostream& s, const SessionResult& r) {
    s << "# Stereo calibration\n\n";
    s << "Session: `" << r.folder.string() << "`  \n";
    s << "Board: " << r.board.inner_columns << " x " << r.board.inner_rows << " inner corners, "
      << fmt(r.board.square_size, 3) << " mm squares  \n";
    s << "Camera " << r.camera_size.width << " x " << r.camera_size.height << " px, projector "
      << r.projector_size.width << " x " << r.projector_size.height << " px  \n";
    int usable = 0;
    for (const SessionPose& p : r.poses)
        usable += p.usable ? 1 : 0;
    s << "Poses: " << r.poses.size() << " found, " << usable
      << " usable; projector coordinates of the corners by `" << to_string(r.method) << "`; skew "
      << (r.stereo.skew_estimated ? "estimated" : "fixed at 0") << "\n\n";
}

void reprojection_section(std::ostream& s, const SessionResult& r) {
    const StereoCalibration& c = r.stereo.calibration;
    s << "## Reprojection error\n\n| | camera RMS (px) | projector RMS (px) |\n|---|---:|---:|\n";
    s << "| OpenCV initialisation (per device, skew 0) | " << fmt(r.stereo.initial_camera_rms, 4)
      << " | " << fmt(r.stereo.initial_projector_rms, 4) << " |\n";
    const bool skew_on = r.stereo.skew_estimated;
    const std::string procedure = std::string(to_string(r.stereo.procedure)) + " bundle adjustment";
    s << "| " << procedure << ", skew " << (skew_on ? "estimated" : "fixed at 0") << " (saved) | "
      << fmt(c.camera_rms, 4) << " | " << fmt(c.projector_rms, 4) << " |\n";
    if (r.other_skew) {
        const StereoCalibration& o = r.other_skew->calibration;
        s << "| " << procedure << ", skew " << (skew_on ? "fixed at 0" : "estimated")
          << " (comparison) | " << fmt(o.camera_rms, 4) << " | " << fmt(o.projector_rms, 4)
          << " |\n";
    }
    s << "\nLM iterations: " << r.stereo.iterations << "\n\n";
    s << "Procedure: " << to_string(r.stereo.procedure)
      << (r.stereo.procedure == StereoProcedure::joint
              ? " (both devices and the boards together, the paper's)"
              : " (the camera from its corners alone places the boards; the projector is "
                "calibrated against them)")
      << ".  \n";
    const auto grid_text = [](const CorrectionGrid& g) {
        return g.empty() ? std::string("none")
                         : std::to_string(g.columns()) + " x " + std::to_string(g.rows()) +
                               " control points, largest displacement " +
                               fmt(g.largest_control_value(), 3) + " px";
    };
    s << "Correction grids: camera " << grid_text(c.camera_correction) << "; projector "
      << grid_text(c.projector_correction) << ".  \n";
    if (r.stereo.dense_rms >= 0) {
        std::size_t samples = 0;
        for (const PoseObservations& o : r.observations)
            samples += o.dense_camera.size();
        s << "Dense samples of the boards' bright parts: " << samples << ", projector residual RMS "
          << fmt(r.stereo.dense_rms, 4) << " px.\n";
    }
    s << "\n";
}

void poses_section(std::ostream& s, const SessionResult& r) {
    const StereoCalibration& c = r.stereo.calibration;
    s << "## Poses\n\n| pose | finder | texture | projector corners | camera RMS (px) | projector "
         "RMS (px) | "
         "status |\n|---|---|---|---:|---:|---:|---|\n";
    for (const SessionPose& p : r.poses) {
        const PoseResidual* res = nullptr;
        for (const PoseResidual& pr : c.poses)
            if (pr.name == p.name)
                res = &pr;
        const ProjectorCorners& pc = p.projector[static_cast<std::size_t>(r.method)];
        s << "| " << p.name << " | " << (p.corners.found ? p.corners.finder : "-") << " | "
          << (p.corners.found ? p.corners.texture : "-") << " | "
          << (p.corners.found
                  ? std::to_string(pc.valid.size() - static_cast<std::size_t>(pc.failed)) + "/" +
                        std::to_string(pc.valid.size())
                  : "-")
          << " | " << (res ? fmt(res->camera_rms, 4) : "-") << " | "
          << (res ? fmt(res->projector_rms, 4) : "-") << " | ";
        if (!p.usable)
            s << "skipped: " << p.skip_reason;
        else if (res && !res->used)
            s << "dropped: " << res->note;
        else if (res && !res->note.empty())
            s << res->note;
        else
            s << "used";
        s << " |\n";
    }
}

// The intrinsics, then camera to projector.
void parameters_section(std::ostream& s, const SessionResult& r) {
    const StereoCalibration& c = r.stereo.calibration;
    const bool skew_on = r.stereo.skew_estimated;
    s << "\n## Intrinsics\n\n"
      << lens_rows(c.camera, r.stereo.camera_sigma, c.projector, r.stereo.projector_sigma);
    if (r.other_skew) {
        const StereoCalibration& o = r.other_skew->calibration;
        s << "\nWith skew " << (skew_on ? "fixed at 0" : "estimated") << ": camera fu "
          << fmt(o.camera.fu, 2) << " fv " << fmt(o.camera.fv, 2) << " cu " << fmt(o.camera.cu, 2)
          << " cv " << fmt(o.camera.cv, 2) << " skew " << fmt(o.camera.skew, 3) << "; projector fu "
          << fmt(o.projector.fu, 2) << " fv " << fmt(o.projector.fv, 2) << " cu "
          << fmt(o.projector.cu, 2) << " cv " << fmt(o.projector.cv, 2) << " skew "
          << fmt(o.projector.skew, 3) << "\n";
    }
    const Vec3 e = euler_deg_from_rotation(c.R);
    const Vec3 centre = c.projector_centre();
    s << "\n## Camera to projector (X_p = R X_c + T)\n\n";
    s << "R as Euler angles (R = Rz(c) Ry(b) Rx(a)): a " << fmt(e[0], 4) << ", b " << fmt(e[1], 4)
      << ", c " << fmt(e[2], 4) << " deg  \n";
    s << "T: " << fmt(c.T[0], 3) << ", " << fmt(c.T[1], 3) << ", " << fmt(c.T[2], 3) << " mm  \n";
    s << "Projector centre in the camera frame: " << fmt(centre[0], 2) << ", " << fmt(centre[1], 2)
      << ", " << fmt(centre[2], 2) << " mm (baseline "
      << fmt(std::sqrt(centre[0] * centre[0] + centre[1] * centre[1] + centre[2] * centre[2]), 2)
      << " mm)\n";
}

// Only for sessions with ground truth (simulated).
void corner_truth_section(std::ostream& s, const SessionResult& r) {
    bool truth = false;
    for (const SessionPose& p : r.poses)
        truth = truth || p.truth_rms[0] >= 0;
    if (!truth)
        return;
    s << "\n## Projector corner methods against ground truth\n\n"
         "RMS distance (projector px) between each method's projector coordinate of a corner "
         "and the "
         "simulator's truth_proj at the detected camera corner.\n\n"
         "| pose | poly | bilinear | homography |\n|---|---:|---:|---:|\n";
    std::array<double, kCornerMethods> sum{};
    std::array<int, kCornerMethods> count{};
    for (const SessionPose& p : r.poses) {
        if (p.truth_rms[0] < 0)
            continue;
        s << "| " << p.name;
        for (int m = 0; m < kCornerMethods; ++m) {
            const double v = p.truth_rms[static_cast<std::size_t>(m)];
            s << " | " << fmt(v, 4);
            if (v >= 0) {
                sum[static_cast<std::size_t>(m)] += v * v * p.truth_points;
                count[static_cast<std::size_t>(m)] += p.truth_points;
            }
        }
        s << " |\n";
    }
    s << "| all";
    for (int m = 0; m < kCornerMethods; ++m)
        s << " | **"
          << fmt(count[static_cast<std::size_t>(m)] ? std::sqrt(sum[static_cast<std::size_t>(m)] /
                                                                count[static_cast<std::size_t>(m)])
                                                    : -1,
                 4)
          << "**";
    s << " |\n";
}

void held_out_section(std::ostream& s, const HeldOutCheck& held_out) {
    s << "\n## Held-out poses\n\nEach pose left out in turn, the pair calibrated from the "
         "others, the left-out board's corners measured by SV (x and y) and compared with "
         "the board: rigid fit RMS (3D, mm), scale error, and the error of every "
         "corner-to-corner length at least half the board's diagonal.\n\n"
         "| pose | corners | distance (mm) | fit RMS (mm) | scale error (ppm) | length error "
         "RMS (mm) | largest (mm) |\n|---|---:|---:|---:|---:|---:|---:|\n";
    for (const HeldOutPose& p : held_out.poses)
        s << "| " << p.name << " | " << p.corners << " | " << fmt(p.distance_mm, 1) << " | "
          << fmt(p.fit_rms_mm, 4) << " | " << fmt(1e6 * p.scale_error, 1) << " | "
          << fmt(p.length_rms_mm, 4) << " | " << fmt(p.length_max_mm, 4) << " |\n";
    s << "| all | | | **" << fmt(held_out.fit_rms_mm, 4) << "** | "
      << fmt(1e6 * held_out.scale_error_rms, 1) << " (RMS) | **" << fmt(held_out.length_rms_mm, 4)
      << "** | **" << fmt(held_out.length_max_mm, 4) << "** |\n";
}

// The calibration's uncertainty in millimetres (trueness.hpp).
void trueness_section(std::ostream& s, const SessionResult& r) {
    s << "\n## Trueness\n\n" << trueness_summary(r.stereo.calibration.trueness);
    if (r.stereo.calibration.trueness.known())
        s << "\nThe shape of a scan (form, flatness) does not depend on it; lengths do, "
             "along depth most: the session's poses and its corners' spread over the image "
             "pin the depth scale. trueness.png: the sigma of a "
          << std::lround(r.stereo.trueness_map.length_mm)
          << " mm length along each part of the image's rays at "
          << std::lround(r.stereo.trueness_map.depth_mm) << " mm.\n";
    if (!r.stereo.next_poses.empty())
        s << "\nTo shrink the depth scale's uncertainty most, the next pose would be: "
          << r.stereo.next_poses.front().words() << " (then about +-"
          << fmt(r.stereo.next_poses.front().sigma_mm, 3) << " mm; `fpp-calib session-check`).\n";
}

void timing_section(std::ostream& s, const SessionResult& r) {
    s << "\n## Timing\n\ndecoding " << fmt(r.seconds_decode, 2) << " s, corners "
      << fmt(r.seconds_corners, 2) << " s, calibration " << fmt(r.seconds_calibration, 2)
      << " s, total " << fmt(r.seconds_total, 2) << " s\n";
}

} // namespace

std::string calibration_summary(const SessionResult& r, const HeldOutCheck* held_out) {
    std::ostringstream s;
    session_section(s, r);
    reprojection_section(s, r);
    poses_section(s, r);
    parameters_section(s, r);
    trueness_section(s, r);
    corner_truth_section(s, r);
    if (held_out)
        held_out_section(s, *held_out);
    timing_section(s, r);
    return s.str();
}

void write_calibration_report(const fs::path& folder, const SessionResult& r,
                              const HeldOutCheck* held_out) {
    if (!report_folder_writable(folder))
        throw InputError(folder, "",
                         "exists and is not a calibration report; choose another --report folder");
    const int columns = r.board.inner_columns, rows = r.board.inner_rows;
    write_report_folder(folder, [&](const fs::path& temp) {
        write_file_synced(temp / "summary.md", calibration_summary(r, held_out));
        for (const SessionPose& p : r.poses) {
            const cv::Mat fig = corner_figure(p, r.method, columns, rows);
            if (!fig.empty())
                save_png(temp / ("corners-" + p.name + ".png"), fig);
        }
        save_png(temp / "residuals-camera.png", residual_figure(r, false));
        save_png(temp / "residuals-projector.png", residual_figure(r, true));
        save_png(temp / "pose-rms.png", rms_figure(r));
        const TruenessMap& map = r.stereo.trueness_map;
        if (r.stereo.calibration.trueness.known() && map.sigma_mm.pixel_count() > 0) {
            float hi = 0;
            for (std::size_t k = 0; k < map.sigma_mm.pixel_count(); ++k)
                if (std::isfinite(map.sigma_mm.data()[k]))
                    hi = std::max(hi, map.sigma_mm.data()[k]);
            save_png(temp / "trueness.png",
                     map_figure(map.sigma_mm, 0.0f, std::max(hi, 1e-4f),
                                "1 sigma of a " + std::to_string(std::lround(map.length_mm)) +
                                    " mm length along depth (mm)"));
        }
    });
}

} // namespace fpp::calib
