// Hybrid calibration report: Markdown summary, fit RMS maps, pose counts,
// plane residuals.

#include "fpp/calib/hybrid_report.hpp"

#include "fpp/calib/plots.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/false_colour.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

namespace fpp::calib {

namespace fs = std::filesystem;

namespace {

float quantile(const Image<float>& image, double q) {
    std::vector<float> v;
    v.reserve(image.pixel_count());
    for (std::size_t i = 0; i < image.pixel_count(); ++i)
        if (std::isfinite(image.data()[i]))
            v.push_back(image.data()[i]);
    if (v.empty())
        return 0.0f;
    const auto k = static_cast<std::ptrdiff_t>(q * double(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[static_cast<std::size_t>(k)];
}

cv::Mat pose_count_figure(const HybridResult& r) {
    Image<float> count(r.pose_count.size());
    for (std::size_t i = 0; i < count.pixel_count(); ++i)
        count.data()[i] = static_cast<float>(r.pose_count.data()[i]);
    return map_figure(count, 0.0f, static_cast<float>(std::max(r.usable_poses, 1)),
                      "board samples per pixel (of " + std::to_string(r.usable_poses) +
                          " usable poses)");
}

cv::Mat plane_residual_figure(const HybridResult& r) {
    const int n = static_cast<int>(r.poses.size());
    const int left = 60, bottom = 40, top = 40, width = std::max(400, left + 40 + 40 * n),
              height = 320;
    cv::Mat out(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    double vmax = 1e-6;
    for (const HybridPose& p : r.poses)
        if (p.usable)
            vmax = std::max(vmax, p.plane_max_mm);
    vmax *= 1.1;
    const int plot_h = height - bottom - top;
    auto y_of = [&](double v) { return static_cast<int>(height - bottom - v / vmax * plot_h); };
    cv::line(out, {left, height - bottom}, {width - 10, height - bottom}, {0, 0, 0}, 1);
    cv::line(out, {left, top}, {left, height - bottom}, {0, 0, 0}, 1);
    for (int t = 0; t <= 4; ++t) {
        const double v = vmax * t / 4;
        cv::putText(out, fixed_text(v, 3), {2, y_of(v) + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.35,
                    {0, 0, 0}, 1, cv::LINE_AA);
    }
    for (int i = 0; i < n; ++i) {
        const HybridPose& p = r.poses[static_cast<std::size_t>(i)];
        const int x = left + 10 + 40 * i;
        if (p.usable) {
            cv::rectangle(out, {x, y_of(p.plane_max_mm)}, {x + 14, height - bottom},
                          {230, 200, 160}, cv::FILLED);
            cv::rectangle(out, {x, y_of(p.plane_rms_mm)}, {x + 14, height - bottom}, {200, 120, 40},
                          cv::FILLED);
        } else {
            cv::putText(out, "x", {x + 2, height - bottom - 6}, cv::FONT_HERSHEY_SIMPLEX, 0.6,
                        {0, 0, 255}, 2);
        }
        cv::putText(out, std::to_string(i + 1), {x, height - bottom + 16}, cv::FONT_HERSHEY_SIMPLEX,
                    0.35, {0, 0, 0}, 1, cv::LINE_AA);
    }
    cv::putText(out, "plane fit per pose (mm): RMS (dark), max (light); x rejected", {left, 24},
                cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1, cv::LINE_AA);
    return out;
}

// Checkerboard sessions: per pose, the stereo model's plane against the
// camera's (signed offset at the board's centre, in um, and the angle):
// a bar far from the others flags a bad pose, all of them off together a
// defect the stereo model lacks or a wrong square size.
cv::Mat sv_offset_figure(const HybridResult& r) {
    const int n = static_cast<int>(r.poses.size());
    const int left = 70, bottom = 40, top = 40, width = std::max(400, left + 40 + 40 * n),
              height = 320;
    cv::Mat out(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    double vmax = 1e-3;
    for (const HybridPose& p : r.poses)
        if (p.usable)
            vmax = std::max(vmax, 1000 * std::fabs(p.sv_offset_mm));
    vmax *= 1.1;
    const int mid = top + (height - bottom - top) / 2, half = (height - bottom - top) / 2;
    auto y_of = [&](double v) { return static_cast<int>(mid - v / vmax * half); };
    cv::line(out, {left, mid}, {width - 10, mid}, {0, 0, 0}, 1);
    cv::line(out, {left, top}, {left, height - bottom}, {0, 0, 0}, 1);
    for (int t = -2; t <= 2; ++t) {
        const double v = vmax * t / 2;
        cv::putText(out, fixed_text(v, 1), {2, y_of(v) + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.35,
                    {0, 0, 0}, 1, cv::LINE_AA);
    }
    for (int i = 0; i < n; ++i) {
        const HybridPose& p = r.poses[static_cast<std::size_t>(i)];
        const int x = left + 10 + 40 * i;
        if (p.usable)
            cv::rectangle(out, {x, std::min(mid, y_of(1000 * p.sv_offset_mm))},
                          {x + 14, std::max(mid, y_of(1000 * p.sv_offset_mm))}, {200, 120, 40},
                          cv::FILLED);
        else
            cv::putText(out, "x", {x + 2, mid - 6}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {0, 0, 255}, 2);
        cv::putText(out, std::to_string(i + 1), {x, height - bottom + 16}, cv::FONT_HERSHEY_SIMPLEX,
                    0.35, {0, 0, 0}, 1, cv::LINE_AA);
    }
    cv::putText(out, "SV plane minus the camera's, at each board's centre (um); x rejected",
                {left, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1, cv::LINE_AA);
    return out;
}

std::string poses_csv(const HybridResult& r) {
    std::ostringstream s;
    s << "pose,usable,points,outliers,distance_mm,tilt_deg,plane_rms_mm,plane_max_mm,"
         "corner_rms_px,lit_fraction,samples,sv_offset_mm,sv_angle_deg,reason\n";
    for (const HybridPose& p : r.poses) {
        std::string reason = p.skip_reason;
        std::replace(reason.begin(), reason.end(), ',', ';');
        s << p.name << "," << (p.usable ? 1 : 0) << "," << p.points << "," << p.outliers << ","
          << fixed_text(p.distance_mm, 3) << "," << fixed_text(p.tilt_deg, 3) << ","
          << fixed_text(p.plane_rms_mm, 5) << "," << fixed_text(p.plane_max_mm, 5) << ","
          << fixed_text(p.corner_rms_px, 5) << "," << fixed_text(p.lit_fraction, 4) << ","
          << p.samples << "," << fixed_text(p.sv_offset_mm, 5) << ","
          << fixed_text(p.sv_angle_deg, 5) << "," << reason << "\n";
    }
    return s.str();
}

} // namespace

std::string hybrid_summary_markdown(const HybridResult& r) {
    std::ostringstream s;
    s << "# Hybrid calibration\n\n```\n" << r.summary() << "```\n\n";
    s << "| Fit RMS (mm) | median | 99 % | max |\n|---|---|---|---|\n";
    for (const auto& [name, image] : {std::pair<const char*, const Image<float>*>{"X", &r.rms_x},
                                      {"Y", &r.rms_y},
                                      {"Z", &r.rms_z}})
        s << "| " << name << " | " << fixed_text(quantile(*image, 0.5), 4) << " | "
          << fixed_text(quantile(*image, 0.99), 4) << " | " << fixed_text(quantile(*image, 1.0), 4)
          << " |\n";
    s << "\n"
      << trueness_summary(r.trueness)
      << "(The calibration's; the table adds its fit's sigma below. Stored in the table and "
         "reported in every scan.json.)\n";
    s << "\nFit RMS: per pixel, the table against the boards' samples. Predicted depth sigma "
         "(sigma-z.png): the table's own uncertainty from its fit residuals.\n";
    if (r.board == BoardDescription::Kind::checkerboard)
        s << "\nEach board is placed by the camera alone (its corners and the calibration's "
             "camera model); the stereo model's best plane through the same pixels is compared "
             "with it (sv-offsets.png, poses.csv): a pose far from the others is a bad pose, "
             "all of them off together a lens defect the stereo model lacks or a square size "
             "that is not the board's. Pixels whose boards gave fewer than the needed samples "
             "get no model (samples.png, black).\n";
    s << "\nFigures: fit-rms-x.png, fit-rms-y.png, fit-rms-z.png (per-pixel fit RMS), "
         "sigma-z.png, samples.png, plane-residuals.png"
      << (r.board == BoardDescription::Kind::checkerboard ? ", sv-offsets.png" : "")
      << "; poses.csv.\n";
    return s.str();
}

void write_hybrid_report(const fs::path& folder, const HybridResult& r) {
    write_report_folder(folder, [&](const fs::path& temp) {
        write_file_synced(temp / "summary.md", hybrid_summary_markdown(r));
        write_file_synced(temp / "poses.csv", poses_csv(r));
        // One colour scale for the three maps: the 99th percentile of Z.
        const float hi = std::max(quantile(r.rms_z, 0.99), 1e-4f);
        save_png(temp / "fit-rms-x.png", map_figure(r.rms_x, 0.0f, hi, "fit RMS X (mm)"));
        save_png(temp / "fit-rms-y.png", map_figure(r.rms_y, 0.0f, hi, "fit RMS Y (mm)"));
        save_png(temp / "fit-rms-z.png", map_figure(r.rms_z, 0.0f, hi, "fit RMS Z (mm)"));
        save_png(temp / "sigma-z.png",
                 map_figure(r.sigma_z, 0.0f, std::max(quantile(r.sigma_z, 0.99), 1e-4f),
                            "predicted depth sigma of the table (mm)"));
        save_png(temp / "samples.png", pose_count_figure(r));
        save_png(temp / "plane-residuals.png", plane_residual_figure(r));
        if (r.board == BoardDescription::Kind::checkerboard)
            save_png(temp / "sv-offsets.png", sv_offset_figure(r));
    });
}

} // namespace fpp::calib
