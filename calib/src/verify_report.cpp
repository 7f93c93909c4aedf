#include "verify_report.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/calib/evaluation.hpp"
#include "fpp/calib/mpe_plot.hpp"
#include "fpp/calib/plots.hpp"
#include "fpp/calib/report_folder.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <sstream>

namespace fpp::calib {

namespace {

using Json = nlohmann::ordered_json;

constexpr double kPi = 3.14159265358979323846;

Json optional_mm(const std::optional<double>& v) {
    return v ? Json(*v) : Json(nullptr);
}

const char* verdict_word(const FigureVerdict& f) {
    return !f.mpe ? "none" : f.passed() ? "pass" : "fail";
}

// What each figure is, for summary.md and the plots.
struct FigureText {
    const char* name;
    const char* title;
    const char* file;
    bool signed_figure;
};
constexpr FigureText kFigureTexts[] = {
    {"SD", "sphere-spacing error SD (measured - certified centre distance)", "sd.png", true},
    {"P_F", "probing error form P_F (radial residual range, 0.3 % excluded)", "probing-form.png",
     false},
    {"P_S", "probing error size P_S (fitted - certified diameter)", "probing-size.png", true},
    {"F", "flatness F (plane residual range, 0.3 % excluded)", "flatness.png", false},
};

const FigureText& text_of(const std::string& name) {
    for (const FigureText& t : kFigureTexts)
        if (name == t.name)
            return t;
    return kFigureTexts[0];
}

// A label per value of a figure: the position, and for per-sphere figures
// the sphere ("3/2": position 3, sphere 2).
std::vector<std::string> value_labels(const FigureVerdict& f,
                                      const std::vector<MeasuredPosition>& positions) {
    std::vector<std::string> labels;
    const bool per_sphere = f.name == "P_F" || f.name == "P_S";
    for (std::size_t p = 0; p < positions.size(); ++p) {
        if (!per_sphere) {
            labels.push_back(std::to_string(p + 1));
            continue;
        }
        for (std::size_t s = 0; s < positions[p].spheres.size(); ++s)
            labels.push_back(positions[p].spheres.size() == 1
                                 ? std::to_string(p + 1)
                                 : std::to_string(p + 1) + "/" + std::to_string(s + 1));
    }
    return labels;
}

Json sphere_json(const MeasuredSphere& s) {
    Json j;
    j["sphere"] = s.index + 1;
    j["certified_diameter_mm"] = s.certified_diameter;
    j["diameter_mm"] = s.diameter;
    j["centre_mm"] = {s.centre[0], s.centre[1], s.centre[2]};
    j["probing_form_mm"] = s.form;
    j["probing_form_all_points_mm"] = s.form_all_points;
    j["probing_size_mm"] = s.size_error;
    j["rms_mm"] = s.rms;
    j["coverage"] = s.coverage;
    j["solid_angle_sr"] = s.coverage * 2 * kPi;
    j["points_used"] = s.points_used;
    if (s.truth_centre)
        j["truth_centre_mm"] = {(*s.truth_centre)[0], (*s.truth_centre)[1], (*s.truth_centre)[2]};
    return j;
}

Json position_json(const MeasuredPosition& p) {
    Json j;
    j["capture"] = p.capture.string();
    j["camera"] = {p.camera.width, p.camera.height};
    if (p.length) {
        j["length_mm"] = *p.length;
        j["sphere_spacing_error_mm"] = *p.spacing_error;
        j["truth_sphere_spacing_error_mm"] = optional_mm(p.truth_spacing_error);
    }
    if (!p.spheres.empty()) {
        j["spheres"] = Json::array();
        for (const MeasuredSphere& s : p.spheres)
            j["spheres"].push_back(sphere_json(s));
    }
    if (p.plane) {
        const MeasuredPlane& f = *p.plane;
        j["plane"] = {{"flatness_mm", f.flatness},
                      {"flatness_all_points_mm", f.flatness_all_points},
                      {"rms_mm", f.rms},
                      {"extent_mm", {f.extent_mm[0], f.extent_mm[1]}},
                      {"points_used", f.points_used}};
    }
    return j;
}

// The used points' residuals of one position per camera pixel, NaN elsewhere.
Image<float> residual_map(const MeasuredPosition& p) {
    Image<float> map(p.camera, 1, std::numeric_limits<float>::quiet_NaN());
    auto put = [&](const std::vector<std::uint32_t>& pixels, const std::vector<double>& values) {
        for (std::size_t k = 0; k < pixels.size() && k < values.size(); ++k)
            map.data()[pixels[k]] = static_cast<float>(values[k]);
    };
    for (const MeasuredSphere& s : p.spheres)
        put(s.pixels, s.residuals);
    if (p.plane)
        put(p.plane->pixels, p.plane->residuals);
    return map;
}

std::string mpe_text(const std::optional<double>& mpe) {
    return mpe ? fixed_text(*mpe, 4) : std::string("-");
}

} // namespace

std::string overall_verdict(const std::vector<FigureVerdict>& figures) {
    bool any = false;
    for (const FigureVerdict& f : figures) {
        if (!f.passed())
            return "fail";
        any = any || f.mpe.has_value();
    }
    return any ? "pass" : "none";
}

std::string verification_json(const VerificationRecord& r) {
    const Artefact& a = r.artefact;
    Json j;
    j["format"] = "fpp-verification/1";
    j["artefact"] = {{"file", a.origin.string()}, {"kind", to_string(a.kind)}, {"name", a.name}};
    if (a.kind == ArtefactKind::plane) {
        j["artefact"]["plane_size_mm"] = {a.plane_width_mm, a.plane_height_mm};
        j["artefact"]["flatness_mm"] = a.flatness_mm;
    } else {
        j["artefact"]["sphere_diameters_mm"] = a.sphere_diameters_mm;
        if (a.kind == ArtefactKind::ball_bar)
            j["artefact"]["centre_distance_mm"] = a.centre_distance_mm;
    }
    j["artefact"]["uncertainty_mm"] = a.uncertainty_mm;
    j["table"] = r.table.string();
    j["verdict"] = overall_verdict(r.figures);
    const MaximumPermissibleErrors& mpe = r.options.mpe;
    j["mpe_mm"] = {{"sphere_spacing", optional_mm(mpe.spacing_mm)},
                   {"probing_form", optional_mm(mpe.form_mm)},
                   {"probing_size", optional_mm(mpe.size_mm)},
                   {"flatness", optional_mm(mpe.flatness_mm)}};
    Json spacing = Json::array(), form = Json::array(), size = Json::array(),
         flatness = Json::array();
    for (const MeasuredPosition& p : r.positions) {
        if (p.spacing_error)
            spacing.push_back(*p.spacing_error);
        if (!p.spheres.empty()) {
            Json f = Json::array(), s = Json::array();
            for (const MeasuredSphere& sphere : p.spheres) {
                f.push_back(sphere.form);
                s.push_back(sphere.size_error);
            }
            form.push_back(f);
            size.push_back(s);
        }
        if (p.plane)
            flatness.push_back(p.plane->flatness);
    }
    j["sphere_spacing_error_mm"] = spacing;
    j["probing_form_mm"] = form;
    j["probing_size_mm"] = size;
    j["flatness_mm"] = flatness;
    j["figures"] = Json::array();
    for (const FigureVerdict& f : r.figures)
        j["figures"].push_back({{"name", f.name},
                                {"largest_magnitude_mm", f.worst},
                                {"mpe_mm", optional_mm(f.mpe)},
                                {"verdict", verdict_word(f)}});
    j["min_coverage"] = r.options.min_coverage;
    j["max_credible_error_mm"] = r.options.max_credible_error_mm;
    j["positions"] = Json::array();
    for (const MeasuredPosition& p : r.positions)
        j["positions"].push_back(position_json(p));
    return j.dump(2) + "\n";
}

std::string verification_summary(const VerificationRecord& r) {
    const Artefact& a = r.artefact;
    std::ostringstream md;
    md << "# Verification (VDI/VDE 2634 part 2)\n\n"
       << "- artefact: `" << a.origin.string() << "`, " << to_string(a.kind)
       << (a.name.empty() ? "" : " \"" + a.name + "\"");
    if (a.kind == ArtefactKind::plane)
        md << ", " << fixed_text(a.plane_width_mm, 1) << " x " << fixed_text(a.plane_height_mm, 1)
           << " mm, certified flatness " << fixed_text(a.flatness_mm, 4) << " mm";
    else {
        md << ", spheres of";
        for (const double d : a.sphere_diameters_mm)
            md << " " << fixed_text(d, 4);
        md << " mm";
        if (a.kind == ArtefactKind::ball_bar)
            md << ", centre distance " << fixed_text(a.centre_distance_mm, 4) << " mm";
    }
    md << ", certificate uncertainty " << fixed_text(a.uncertainty_mm, 4) << " mm (1 sigma)\n"
       << "- table: `" << r.table.string() << "`\n"
       << "- positions: " << r.positions.size() << "\n"
       << "- verdict: **" << overall_verdict(r.figures) << "**\n\n"
       << "## Figures\n\n| figure | largest magnitude (mm) | MPE (mm) | verdict |\n"
       << "|---|---:|---:|---|\n";
    for (const FigureVerdict& f : r.figures)
        md << "| " << text_of(f.name).title << " | " << fixed_text(f.worst, 4) << " | "
           << mpe_text(f.mpe) << " | " << verdict_word(f) << " |\n";
    md << "\nA figure passes when its magnitude is within its MPE at every position; "
          "without an MPE it gets no verdict.\n\n## Positions\n\n";
    if (a.kind == ArtefactKind::plane) {
        md << "| position | capture | F (mm) | F, all points (mm) | RMS (mm) | extent (mm) | "
              "points "
              "|\n|---:|---|---:|---:|---:|---|---:|\n";
        for (std::size_t k = 0; k < r.positions.size(); ++k) {
            const MeasuredPlane& p = *r.positions[k].plane;
            md << "| " << k + 1 << " | `" << r.positions[k].capture.string() << "` | "
               << fixed_text(p.flatness, 4) << " | " << fixed_text(p.flatness_all_points, 4)
               << " | " << fixed_text(p.rms, 4) << " | " << fixed_text(p.extent_mm[0], 1) << " x "
               << fixed_text(p.extent_mm[1], 1) << " | " << p.points_used << " |\n";
        }
    } else {
        md << "| position | sphere | diameter (mm) | P_F (mm) | P_S (mm) | coverage | points | "
              "SD (mm) | SD from the truth (mm) "
              "|\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
        for (std::size_t k = 0; k < r.positions.size(); ++k) {
            const MeasuredPosition& p = r.positions[k];
            for (const MeasuredSphere& s : p.spheres) {
                const bool first = s.index == 0;
                md << "| " << k + 1 << " | " << s.index + 1 << " | " << fixed_text(s.diameter, 4)
                   << " | " << fixed_text(s.form, 4) << " | " << fixed_text(s.size_error, 4)
                   << " | " << fixed_text(s.coverage, 2) << " | " << s.points_used << " | "
                   << (first && p.spacing_error ? fixed_text(*p.spacing_error, 4) : "") << " | "
                   << (first && p.truth_spacing_error ? fixed_text(*p.truth_spacing_error, 4) : "")
                   << " |\n";
            }
        }
        md << "\nCoverage: the share of the hemisphere facing the camera that the points used "
              "cover. Spheres are numbered by their certified diameters, or from left to right "
              "in the image when those are alike.\n\nCaptures:\n\n";
        for (std::size_t k = 0; k < r.positions.size(); ++k)
            md << k + 1 << ". `" << r.positions[k].capture.string() << "`\n";
    }
    md << "\n## Plots\n\n";
    for (const FigureVerdict& f : r.figures)
        md << "- `" << text_of(f.name).file << "`: " << text_of(f.name).title << "\n";
    md << "- `residuals-N.png`: position N, the fit residual of every point used per camera "
          "pixel ("
       << (a.kind == ArtefactKind::plane ? "+ towards the camera" : "+ outside") << ")\n";
    return md.str();
}

void write_verification_report(const std::filesystem::path& folder, const VerificationRecord& r) {
    const std::string json = verification_json(r);
    const std::string summary = verification_summary(r);
    std::vector<std::pair<std::string, cv::Mat>> pngs;
    for (const FigureVerdict& f : r.figures) {
        const FigureText& t = text_of(f.name);
        const bool per_sphere = f.name == "P_F" || f.name == "P_S";
        pngs.emplace_back(t.file,
                          mpe_plot(f.values, value_labels(f, r.positions), f.mpe, t.signed_figure,
                                   per_sphere ? "position / sphere" : "position", "mm", t.title));
    }
    for (std::size_t k = 0; k < r.positions.size(); ++k) {
        const Image<float> map = residual_map(r.positions[k]);
        std::vector<double> values;
        for (std::size_t i = 0; i < map.pixel_count(); ++i)
            if (std::isfinite(map.data()[i]))
                values.push_back(double(map.data()[i]));
        pngs.emplace_back("residuals-" + std::to_string(k + 1) + ".png",
                          signed_map_figure(map, symmetric_limit(values, 0.995),
                                            "position " + std::to_string(k + 1) +
                                                ": fit residual per camera pixel"));
    }
    write_report_folder(folder, [&](const std::filesystem::path& temp) {
        write_file_synced(temp / "summary.md", summary);
        write_file_synced(temp / "verification.json", json);
        for (const auto& [name, image] : pngs)
            save_png(temp / name, image);
    });
}

} // namespace fpp::calib
