// The paper experiments' scans (see paper_stages.hpp): each scene rendered
// with the rig's noise and noise-free, reconstructed by every method and
// compared with the truth, with its shape fits; the ball bars; the relief's
// comparison of the paper's SV with its tables. The relief's timings are in
// paper_timing.cpp.

#include "fpp/calib/evaluation.hpp"
#include "fpp/calib/plots.hpp"
#include "fpp/calib/shape_fit.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/table_kernel.hpp"
#include "paper_stages.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fpp::calib::paper {

namespace fs = std::filesystem;

namespace {

// Keeps the pixels of `mask` (1 = set) whose (2r+1) x (2r+1) neighbourhood is
// all set (separable minimum filter; outside the image counts as unset).
void erode(std::vector<std::uint8_t>& mask, Size size, int r) {
    const int w = size.width, h = size.height;
    std::vector<std::uint8_t> tmp(mask.size());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::uint8_t v = 1;
            for (int k = x - r; k <= x + r && v; ++k)
                v = (k >= 0 && k < w) ? mask[std::size_t(y) * std::size_t(w) + std::size_t(k)] : 0;
            tmp[std::size_t(y) * std::size_t(w) + std::size_t(x)] = v;
        }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::uint8_t v = 1;
            for (int k = y - r; k <= y + r && v; ++k)
                v = (k >= 0 && k < h) ? tmp[std::size_t(k) * std::size_t(w) + std::size_t(x)] : 0;
            mask[std::size_t(y) * std::size_t(w) + std::size_t(x)] = v;
        }
}

// The points of `cloud` at the pixels of `mask` (organised) where it has one.
CloudPoints masked_points(const PointCloud& cloud, const std::vector<std::uint8_t>& mask) {
    CloudPoints out;
    out.organised = cloud.size();
    const float* xyz = cloud.xyz.data();
    for (std::size_t i = 0; i < mask.size(); ++i)
        if (mask[i] && finite_point(xyz + 3 * i)) {
            out.points.push_back(
                {double(xyz[3 * i]), double(xyz[3 * i + 1]), double(xyz[3 * i + 2])});
            out.pixels.push_back(static_cast<std::uint32_t>(i));
        }
    return out;
}

} // namespace

DecodeResult Run::decode_capture(const sim::SimulatedCapture& capture,
                                 const fs::path& folder) const {
    CaptureSet set;
    set.folder = folder;
    set.manifest = capture.manifest;
    set.frames = capture.frames;
    return decode(set, decode_options_);
}

Reconstructions Run::reconstruct_all(const DecodeResult& decoded) const {
    Reconstructions r;
    r.clouds.resize(count());
    for (std::size_t m = 0; m < count(); ++m) {
        const Method& method = record_.methods[m];
        if (method.is_table())
            apply_table(method.table, decoded.proj_x, r.clouds[m]);
        else
            method.sv->reconstruct(decoded, ReconstructAxes::x, r.clouds[m]);
    }
    const std::size_t n = decoded.camera.area();
    r.common.assign(n, 1);
    r.points.assign(count(), 0);
    for (std::size_t m = 0; m < count(); ++m) {
        const float* xyz = r.clouds[m].xyz.data();
        for (std::size_t i = 0; i < n; ++i) {
            const bool ok = finite_point(xyz + 3 * i);
            r.points[m] += ok ? 1 : 0;
            if (!ok && record_.methods[m].in_common)
                r.common[i] = 0;
        }
    }
    erode(r.common, decoded.camera, kEdgeMarginPx);
    r.common_count = std::size_t(std::count(r.common.begin(), r.common.end(), 1));
    return r;
}

Run::NoisyScan Run::process_scan(ScanSummary& s, const sim::Scene& scene,
                                 std::unique_ptr<sim::Renderer> renderer, int seed_index,
                                 bool save) {
    const fs::path folder = folder_ / "scans" / s.key;
    say("scan '" + s.key + "': rendering with the rig's noise");
    if (!renderer)
        renderer = std::make_unique<sim::Renderer>(rig(), scene, options().threads);
    NoisyScan noisy;
    {
        const sim::SimulatedCapture capture =
            sim::simulate(*renderer, scan_sequence_, scan_seed(seed_index));
        if (save)
            sim::write_simulated_capture(folder, capture);
        noisy.decoded = decode_capture(capture, folder);
        noisy.recon = reconstruct_all(noisy.decoded);
        s.points = noisy.recon.points;
        s.common = noisy.recon.common_count;
        for (std::size_t m = 0; m < count(); ++m) {
            const TruthComparison t = compare_with_truth(
                masked_points(noisy.recon.clouds[m], noisy.recon.common), capture.truth_xyz);
            s.truth_noisy.push_back(t.dz);
            s.shape_noisy.push_back(t.dz_shape);
            s.compared_noisy = t.compared;
            s.truth_pixels = t.truth_pixels;
        }
    }
    renderer.reset();
    say("scan '" + s.key + "': " + std::to_string(s.common) +
        " pixels with a point from every method");
    fit_shapes(s, noisy.recon, true);

    say("scan '" + s.key + "': rendering noise-free (read noise 0, no shot noise)");
    {
        const sim::Renderer clean(clean_rig_, scene, options().threads);
        const sim::SimulatedCapture capture =
            sim::simulate(clean, scan_sequence_, scan_seed(seed_index));
        const DecodeResult decoded = decode_capture(capture, folder);
        const Reconstructions recon = reconstruct_all(decoded);
        fit_shapes(s, recon, false);
        std::vector<TruthComparison> cmp;
        for (std::size_t m = 0; m < count(); ++m) {
            CloudPoints points = masked_points(recon.clouds[m], recon.common);
            cmp.push_back(compare_with_truth(points, capture.truth_xyz));
            s.truth_clean.push_back(cmp.back().dz);
            s.shape_clean.push_back(cmp.back().dz_shape);
            s.distance_clean.push_back(cmp.back().distance);
            s.compared_clean = cmp.back().compared;
            if (const FrameTurn* turn = record_.turn_of(record_.methods[m].procedure)) {
                turn_points(*turn, points.points);
                s.turned_clean.push_back(compare_with_truth(points, capture.truth_xyz).dz);
            } else {
                s.turned_clean.push_back(cmp.back().dz);
            }
        }
        if (save) {
            // Error maps on one colour scale, the paper's SV's.
            const std::size_t reference = record_.find("sv-paper");
            const double limit = symmetric_limit(cmp[reference].dz_values);
            for (std::size_t m = 0; m < count(); ++m)
                png("truth-" + s.key + "-" + record_.methods[m].key + ".png",
                    signed_map_figure(cmp[m].dz_map, limit,
                                      s.key + " noise-free: Z - Z true, " +
                                          record_.methods[m].title));
        }
    }
    for (std::size_t m = 0; m < count(); ++m) {
        const std::string k = record_.methods[m].key;
        add(s.key + ".points." + k, double(s.points[m]), "");
        add("truth." + s.key + ".noisy." + k + ".rms", s.truth_noisy[m].rms, "mm");
        add("truth." + s.key + ".noisy." + k + ".mean", s.truth_noisy[m].mean, "mm");
        add("truth." + s.key + ".noise_free." + k + ".rms", s.truth_clean[m].rms, "mm");
        add("truth." + s.key + ".noise_free." + k + ".mean", s.truth_clean[m].mean, "mm");
        add("truth." + s.key + ".noise_free." + k + ".std", s.truth_clean[m].stddev, "mm");
        add("truth." + s.key + ".noisy." + k + ".shape_rms", s.shape_noisy[m].rms, "mm");
        add("truth." + s.key + ".noise_free." + k + ".shape_rms", s.shape_clean[m].rms, "mm");
        add("truth." + s.key + ".noise_free." + k + ".distance_rms", s.distance_clean[m].rms, "mm");
        add("truth." + s.key + ".noise_free." + k + ".turned_rms", s.turned_clean[m].rms, "mm");
        add("truth." + s.key + ".noise_free." + k + ".turned_mean", s.turned_clean[m].mean, "mm");
    }
    add(s.key + ".truth_pixels", double(s.truth_pixels), "");
    add(s.key + ".common_points", double(s.common), "");
    std::string line = "scan '" + s.key + "' Z error vs truth, RMS noisy / noise-free:";
    for (std::size_t m = 0; m < count(); ++m)
        line += " " + record_.methods[m].key + " " + fixed_text(s.truth_noisy[m].rms, 4) + " / " +
                fixed_text(s.truth_clean[m].rms, 4);
    say(line + " mm");
    return noisy;
}

void Run::fit_shapes(ScanSummary& s, const Reconstructions& recon, bool noisy) {
    std::vector<double> fit_rms(count(), kNaN), diameter(count(), kNaN),
        diameter_error(count(), kNaN);
    if (s.fit == FitKind::none)
        return;
    std::vector<CloudPoints> points(count());
    std::vector<std::vector<double>> residuals(count());
    for (std::size_t m = 0; m < count(); ++m) {
        points[m] = masked_points(recon.clouds[m], recon.common);
        try {
            if (s.fit == FitKind::plane) {
                const PlaneFit f = fit_plane(points[m].points);
                fit_rms[m] = f.fit.rms;
                residuals[m] = f.fit.residuals;
            } else if (s.fit == FitKind::cylinder) {
                const CylinderFigures f = cylinder_figures(points[m].points, s.nominal_diameter);
                fit_rms[m] = f.fit.fit.rms;
                diameter[m] = f.diameter;
                diameter_error[m] = f.diameter_error.value_or(kNaN);
                residuals[m] = f.fit.fit.residuals;
            } else {
                const ProbingFigures f = probing_figures(points[m].points, s.nominal_diameter);
                fit_rms[m] = f.fit.fit.rms;
                diameter[m] = f.diameter;
                diameter_error[m] = f.size_error.value_or(kNaN);
                residuals[m] = f.fit.fit.residuals;
            }
        } catch (const FitError& e) {
            s.fit_note += record_.methods[m].title + (noisy ? "" : " (noise-free)") +
                          ": fit failed (" + e.what() + "). ";
        }
    }
    if (!noisy) {
        s.fit_rms_clean = fit_rms;
        s.diameter_clean = diameter;
        for (std::size_t m = 0; m < count(); ++m)
            if (std::isfinite(fit_rms[m])) {
                add(s.key + ".fit_rms_noise_free." + record_.methods[m].key, fit_rms[m], "mm");
                if (s.fit != FitKind::plane)
                    add(s.key + ".diameter_noise_free." + record_.methods[m].key, diameter[m],
                        "mm");
            }
        return;
    }
    s.fit_rms = fit_rms;
    s.diameter = diameter;
    s.diameter_error = diameter_error;
    const char* fit_name = s.fit == FitKind::plane      ? "plane"
                           : s.fit == FitKind::cylinder ? "cylinder"
                                                        : "sphere";
    for (std::size_t m = 0; m < count(); ++m) {
        if (!std::isfinite(s.fit_rms[m]))
            continue;
        const std::string& k = record_.methods[m].key;
        add(s.key + ".fit_rms." + k, s.fit_rms[m], "mm");
        if (s.fit != FitKind::plane) {
            add(s.key + ".diameter." + k, s.diameter[m], "mm");
            add(s.key + ".diameter_error." + k, s.diameter_error[m], "mm");
        }
    }
    const std::size_t reference = record_.find("sv-paper");
    if (residuals[reference].empty())
        return;
    const double limit = symmetric_limit(residuals[reference]);
    std::vector<HistogramSeries> series;
    for (std::size_t m = 0; m < count(); ++m)
        if (!residuals[m].empty() && (m == reference || record_.methods[m].is_default))
            series.push_back({record_.methods[m].title, residuals[m]});
    png(s.key + "-fit-histogram.png",
        histogram_figure(series, -limit, limit, std::string(fit_name) + " fit residual (mm)",
                         s.key + ": " + fit_name + "-fit residuals (noisy scan)"));
    for (std::size_t m = 0; m < count(); ++m)
        if (!residuals[m].empty())
            png(s.key + "-fit-map-" + record_.methods[m].key + ".png",
                signed_map_figure(values_image(points[m], residuals[m]), limit,
                                  s.key + ": " + fit_name + "-fit residual, " +
                                      record_.methods[m].title));
}

sim::Scene Run::plane_scene() {
    sim::Scene scene;
    scene.add(std::make_unique<sim::Plane>(
        sim::Pose::from_euler_deg({0, 0, kPlaneDistance}, kPlaneTiltXDeg, kPlaneTiltYDeg, 0),
        kPlaneWidth, kPlaneHeight, 0.9));
    return scene;
}

sim::Scene Run::cylinder_scene() {
    sim::Scene scene;
    const double r = kCylinderDiameter / 2;
    scene.add(std::make_unique<sim::Cylinder>(Vec3{0, 0, kCylinderFront + r}, Vec3{0, 1, 0}, r,
                                              kCylinderLength, 0.85));
    return scene;
}

sim::Scene Run::sphere_scene() {
    sim::Scene scene;
    scene.add(std::make_unique<sim::Sphere>(Vec3{0, 0, kSphereCentreZ}, kSphereDiameter / 2, 0.9));
    return scene;
}

sim::Scene Run::relief_scene(double scale) {
    std::vector<sim::ReliefBump> bumps = sim::Relief::face_bumps();
    for (sim::ReliefBump& b : bumps) {
        b.x0 *= scale;
        b.y0 *= scale;
        b.amplitude *= scale;
        b.radius_x *= scale;
        b.radius_y *= scale;
    }
    sim::Scene scene;
    scene.add(std::make_unique<sim::Relief>(
        sim::Pose{{0, 0, kReliefBaseZ}, {1, 0, 0, 0, 1, 0, 0, 0, 1}}, kReliefWidth * scale,
        kReliefHeight * scale, std::move(bumps), 0.85));
    return scene;
}

void Run::run_shape(const std::string& key, const std::string& title, FitKind fit, double nominal,
                    const sim::Scene& scene, int seed_index) {
    ScanSummary s;
    s.key = key;
    s.title = title;
    s.fit = fit;
    s.nominal_diameter = nominal;
    process_scan(s, scene, nullptr, seed_index);
    record_.scans.push_back(std::move(s));
}

void Run::run_plane() {
    ScanSummary s;
    s.key = "plane";
    s.title = "Experiment 1: inclined plane (230 x 175 mm, ~20 deg, 480 mm)";
    s.fit = FitKind::plane;
    const NoisyScan noisy = process_scan(s, plane_scene(), nullptr, 11);
    record_.scans.push_back(std::move(s));
    run_windows(noisy.decoded, noisy.recon);
}

void Run::run_ball_bars() {
    // Centres of the spheres between about 430 and 530 mm: inside the
    // depths every calibration session reaches (board centres 400 to
    // 560 mm).
    const std::vector<std::pair<Vec3, Vec3>> places = {
        {{0, 0, 480}, {1, 0, 0}},       {{0, 0, 480}, {0.87, 0, 0.5}},
        {{0, 0, 480}, {-0.87, 0, 0.5}}, {{0, 0, 480}, {0.55, 0.66, 0.5}},
        {{0, 0, 480}, {0.7, 0.5, 0.5}}, {{0, 0, 480}, {-0.7, 0.5, 0.5}},
        {{0, 10, 500}, {0.9, 0.44, 0}}};
    for (std::size_t k = 0; k < places.size(); ++k) {
        BallBarPosition b;
        b.centre = places[k].first;
        b.axis = places[k].second;
        sim::Scene scene;
        sim::add_ball_bar(scene, b.centre, b.axis, kBallBarLength, kBallDiameter / 2, 0.85);
        ScanSummary s;
        s.key = "ball-bar-" + std::to_string(k + 1);
        s.title = "ball bar " + std::to_string(k + 1);
        say("ball bar " + std::to_string(k + 1) + " of " + std::to_string(places.size()));
        for (const bool noisy : {true, false}) {
            const sim::Renderer renderer(noisy ? rig() : clean_rig_, scene, options().threads);
            const sim::SimulatedCapture capture =
                sim::simulate(renderer, scan_sequence_, scan_seed(20 + int(k)));
            const DecodeResult decoded = decode_capture(capture, folder_);
            const Reconstructions recon = reconstruct_all(decoded);
            std::vector<double>& spacing = noisy ? b.spacing_error : b.spacing_error_clean;
            for (std::size_t m = 0; m < count(); ++m) {
                // Each method's own points (a table covers what its boards
                // reached), away from the spheres' silhouettes.
                std::vector<std::uint8_t> own(decoded.camera.area());
                for (std::size_t i = 0; i < own.size(); ++i)
                    own[i] = finite_point(recon.clouds[m].xyz.data() + 3 * i) ? 1 : 0;
                erode(own, decoded.camera, kEdgeMarginPx);
                const CloudPoints points = masked_points(recon.clouds[m], own);
                double error = kNaN, size = kNaN;
                try {
                    const BallBarFigures f =
                        ball_bar_figures(points.points, kBallBarLength, kBallDiameter);
                    // Both spheres must be seen: one sphere split into
                    // two clusters (the other outside the method's
                    // range) is no ball bar.
                    if (f.fit.distance > 0.5 * kBallBarLength) {
                        error = f.spacing_error.value_or(kNaN);
                        size = std::max(std::fabs(f.size_error_first.value_or(kNaN)),
                                        std::fabs(f.size_error_second.value_or(kNaN)));
                    }
                } catch (const FitError&) {
                    // NaN: no fit (too few points)
                }
                spacing.push_back(error);
                if (noisy)
                    b.size_error.push_back(size);
            }
        }
        for (std::size_t m = 0; m < count(); ++m) {
            const std::string base =
                "ball_bar." + std::to_string(k + 1) + "." + record_.methods[m].key;
            add(base + ".spacing_error", b.spacing_error[m], "mm");
            add(base + ".spacing_error_noise_free", b.spacing_error_clean[m], "mm");
            add(base + ".size_error", b.size_error[m], "mm");
        }
        record_.ball_bars.push_back(std::move(b));
    }
}

void Run::run_relief() {
    const double target = kReliefPixelsFullSize / double(options().binning * options().binning);
    say("relief: sizing it so that about " + std::to_string(static_cast<long>(target)) +
        " camera pixels see it");
    double scale = 1;
    std::unique_ptr<sim::Renderer> renderer;
    std::size_t seen = 0;
    for (int round = 0; round < 3; ++round) {
        renderer = std::make_unique<sim::Renderer>(rig(), relief_scene(scale), options().threads);
        const Image<float>& proj = renderer->truth_projector();
        seen = 0;
        for (std::size_t i = 0; i < proj.pixel_count(); ++i)
            seen += std::isfinite(proj.data()[2 * i]) ? 1 : 0;
        say("  scale " + fixed_text(scale, 4) + ": " + std::to_string(seen) + " lit pixels see it");
        if (seen == 0)
            throw std::runtime_error("relief: no camera pixel sees the relief");
        if (round == 2)
            break;
        scale = std::clamp(scale * std::sqrt(target / double(seen)), 0.3, 1.5);
    }
    ReliefSummary& relief = record_.relief;
    relief.scale = scale;
    relief.pixels_seen = seen;
    add("relief.scale", scale, "");
    add("relief.pixels_seen", double(seen), "");

    ScanSummary s;
    s.key = "relief";
    s.title = "Experiment 3: freeform relief (face)";
    s.fit = FitKind::none;
    const NoisyScan noisy = process_scan(s, relief_scene(scale), std::move(renderer), 14);
    record_.scans.push_back(std::move(s));

    // The paper's comparison: its SV against its hybrid tables, per pixel.
    const std::size_t sv = record_.find("sv-paper");
    const CloudPoints sv_points = cloud_points(noisy.recon.clouds[sv]);
    std::vector<std::vector<double>> differences;
    for (std::size_t m = 0; m < count(); ++m) {
        const Method& method = record_.methods[m];
        if (method.procedure != Procedure::paper || !method.is_table())
            continue;
        const CloudDistance d = compare_per_pixel(sv_points, cloud_points(noisy.recon.clouds[m]));
        relief.compared_methods.push_back(m);
        relief.distance_rms.push_back(d.distance.rms);
        relief.dz_rms.push_back(d.dz.rms);
        relief.matched.push_back(d.matched);
        add("relief.difference." + method.key + ".distance_rms", d.distance.rms, "mm");
        add("relief.difference." + method.key + ".dz_rms", d.dz.rms, "mm");
        png("relief-difference-" + method.key + ".png",
            signed_map_figure(d.dz_map, symmetric_limit(d.values),
                              "relief: Z(SV) - Z(" + method.title + ")"));
        differences.push_back(d.values);
    }
    if (!differences.empty()) {
        std::vector<HistogramSeries> series;
        for (std::size_t k = 0; k < differences.size(); ++k)
            series.push_back(
                {"SV - " + record_.methods[relief.compared_methods[k]].key, differences[k]});
        const double limit = symmetric_limit(differences[0]);
        png("relief-difference-histogram.png",
            histogram_figure(series, -limit, limit, "Z(SV) - Z(hybrid) per pixel (mm)",
                             "relief: the paper's SV vs its hybrid tables"));
    }
    time_relief(noisy.decoded);
}

} // namespace fpp::calib::paper
