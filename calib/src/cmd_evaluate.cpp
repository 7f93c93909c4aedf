// fpp-calib evaluate CLOUD.ply [--fit plane|sphere|cylinder|ball-bar]
//     [--nominal-diameter MM] [--nominal-length MM] [--reject-sigma K]
//     [--truth CAPTURE] [--compare OTHER.ply] [--match pixel|nearest]
//     [--label NAME] [--other-label NAME] --out DIR
//
// Evaluates a reconstruction (and optionally a second one of the same scene,
// e.g. SV against hybrid) and writes a report folder, as a whole, only when
// everything succeeded:
//   summary.md                   the figures as Markdown tables (also printed)
//   figures.csv                  name,value,unit; names start with "cloud."
//                                (CLOUD), "other." (OTHER) or "compare."
//   fit-histogram.png            fit residuals, both clouds overlaid
//   fit-map.png, fit-map-other.png       fit residual per camera pixel
//   truth-histogram.png          Z error against the ground truth
//   truth-map.png, truth-map-other.png   Z error per camera pixel
//   difference-histogram.png     CLOUD - OTHER (Z per pixel, or distances)
//   difference-map.png           Z difference per camera pixel
// Maps need organised clouds (pixel indices, as fpp-calib reconstruct
// writes); without them the fit maps are left out (said in summary.md).

#include "cli_util.hpp"
#include "commands.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/calib/evaluation.hpp"
#include "fpp/calib/plots.hpp"
#include "fpp/calib/report_folder.hpp"
#include "fpp/calib/shape_fit.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/point_cloud.hpp"

#include <opencv2/core.hpp>

#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>

namespace fpp::calib {

namespace {

namespace fs = std::filesystem;

struct EvaluateArgs {
    std::string cloud;
    std::string fit;
    double nominal_diameter = 0;
    double nominal_length = 0;
    double reject_sigma = 0;
    std::string truth;
    std::string compare;
    std::string match = "pixel";
    std::string label;
    std::string other_label;
    std::string out;
    // Which options were given.
    CLI::Option* nominal_diameter_option = nullptr;
    CLI::Option* nominal_length_option = nullptr;
    CLI::Option* other_label_option = nullptr;
    CLI::Option* match_option = nullptr;
};

// One figure of one cloud: `key` is its name in figures.csv after the
// cloud's prefix, `title` its row in summary.md.
struct Item {
    std::string key;
    std::string title;
    double value = 0;
    std::string unit;
    int digits = 4; // -1: a count
};

// One evaluated cloud.
struct Subject {
    fs::path path;
    std::string label;
    std::string prefix; // "cloud" or "other"
    CloudPoints cloud;
    // Fit: residual per point, inlier mask, figures, description.
    std::vector<double> residuals;
    std::vector<std::uint8_t> inlier;
    std::vector<double> used_residuals;
    std::vector<Item> fit_items;
    std::string fit_message;
    std::optional<TruthComparison> truth;
    std::vector<Item> truth_items;
};

std::string report_size_text(Size s) {
    return std::to_string(s.width) + " x " + std::to_string(s.height);
}

Item mm(std::string key, std::string title, double value, int digits = 4) {
    return {std::move(key), std::move(title), value, "mm", digits};
}
Item count(std::string key, std::string title, std::size_t value) {
    return {std::move(key), std::move(title), static_cast<double>(value), "", -1};
}

std::string value_text(const Item& item) {
    if (item.digits < 0)
        return fixed_text(item.value, 0);
    return fixed_text(item.value, item.digits);
}

Subject load_subject(const fs::path& path, std::string label, std::string prefix) {
    std::error_code ec;
    if (!fs::exists(path, ec))
        throw InputError(path, "", "no such file");
    if (!fs::is_regular_file(path, ec))
        throw InputError(path, "", "is not a file");
    Subject s;
    s.path = path;
    s.label = std::move(label);
    s.prefix = std::move(prefix);
    s.cloud = cloud_points(read_ply(path), path);
    if (s.cloud.points.empty())
        throw InputError(path, "element vertex", "the cloud has no valid points");
    return s;
}

const char* organised_hint =
    "(obj_info organised_width/height and a 'pixel' vertex property, as fpp-calib reconstruct "
    "writes)";

void require_organised(const Subject& s, const std::string& what) {
    if (!s.cloud.is_organised())
        throw InputError(s.path, "pixel",
                         "the cloud has no camera pixel indices " + std::string(organised_hint) +
                             "; " + what + " needs an organised cloud");
}

// ---------------------------------------------------------------- fits

std::optional<double> given(const CLI::Option* option, double value) {
    return option && option->count() ? std::optional<double>(value) : std::nullopt;
}

void residual_items(Subject& s, const FitOptions& options) {
    s.used_residuals.clear();
    for (std::size_t i = 0; i < s.residuals.size(); ++i)
        if (s.inlier[i])
            s.used_residuals.push_back(s.residuals[i]);
    const ErrorStats e = error_stats(s.used_residuals);
    s.fit_items.insert(
        s.fit_items.begin(),
        {count("fit.points_used", "points used", s.used_residuals.size()),
         count("fit.points_rejected",
               options.reject_sigma > 0
                   ? "points rejected (beyond " + fixed_text(options.reject_sigma, 1) + " sigma)"
                   : "points rejected (rejection off)",
               s.residuals.size() - s.used_residuals.size()),
         mm("fit.rms", "RMS residual", e.rms), mm("fit.min", "smallest residual", e.min),
         mm("fit.max", "largest residual", e.max)});
}

void fit_subject(Subject& s, const std::string& shape, const EvaluateArgs& args) {
    FitOptions options;
    options.reject_sigma = args.reject_sigma;
    const auto nominal_d = given(args.nominal_diameter_option, args.nominal_diameter);
    const auto nominal_l = given(args.nominal_length_option, args.nominal_length);
    const std::vector<Vec3>& p = s.cloud.points;
    auto& items = s.fit_items;
    try {
        if (shape == "plane") {
            const FlatnessFigures f = flatness_figures(p, options);
            s.residuals = f.fit.fit.residuals;
            s.inlier = f.fit.fit.inlier;
            s.fit_message = f.fit.fit.message;
            items = {mm("plane.flatness", "flatness F (residual range)", f.flatness),
                     mm("plane.flatness_trimmed",
                        "flatness F, 0.3 % of points excluded (plane refitted)", f.trimmed.range),
                     count("plane.trimmed_excluded", "points excluded for it", f.trimmed.excluded),
                     {"plane.normal_x", "normal x (towards the camera)", f.fit.normal[0], "", 6},
                     {"plane.normal_y", "normal y", f.fit.normal[1], "", 6},
                     {"plane.normal_z", "normal z", f.fit.normal[2], "", 6},
                     mm("plane.point_x", "centroid x", f.fit.point[0], 3),
                     mm("plane.point_y", "centroid y", f.fit.point[1], 3),
                     mm("plane.point_z", "centroid z", f.fit.point[2], 3)};
        } else if (shape == "sphere") {
            const ProbingFigures f = probing_figures(p, nominal_d, options);
            s.residuals = f.fit.fit.residuals;
            s.inlier = f.fit.fit.inlier;
            s.fit_message = f.fit.fit.message;
            items = {mm("sphere.diameter", "diameter", f.diameter),
                     mm("sphere.form", "probing error form P_F (radial residual range)", f.form),
                     mm("sphere.form_trimmed", "P_F, 0.3 % of points excluded (refitted)",
                        f.form_trimmed.range)};
            if (f.size_error)
                items.push_back(mm("sphere.size_error",
                                   "probing error size P_S (fitted - nominal diameter)",
                                   *f.size_error));
            items.push_back(mm("sphere.centre_x", "centre x", f.fit.centre[0], 3));
            items.push_back(mm("sphere.centre_y", "centre y", f.fit.centre[1], 3));
            items.push_back(mm("sphere.centre_z", "centre z", f.fit.centre[2], 3));
        } else if (shape == "cylinder") {
            const CylinderFigures f = cylinder_figures(p, nominal_d, options);
            s.residuals = f.fit.fit.residuals;
            s.inlier = f.fit.fit.inlier;
            s.fit_message = f.fit.fit.message;
            items = {mm("cylinder.diameter", "diameter", f.diameter),
                     mm("cylinder.form", "form (radial residual range)", f.form)};
            if (f.diameter_error)
                items.push_back(mm("cylinder.diameter_error", "diameter error (fitted - nominal)",
                                   *f.diameter_error));
            items.push_back({"cylinder.arc", "arc covered", f.fit.arc_degrees, "deg", 1});
            items.push_back(mm("cylinder.length", "length covered", f.fit.length, 1));
            items.push_back({"cylinder.axis_x", "axis x", f.fit.axis[0], "", 6});
            items.push_back({"cylinder.axis_y", "axis y", f.fit.axis[1], "", 6});
            items.push_back({"cylinder.axis_z", "axis z", f.fit.axis[2], "", 6});
        } else { // ball-bar
            const BallBarFigures f = ball_bar_figures(p, nominal_l, nominal_d, options);
            // Residuals back in the cloud's point order.
            s.residuals.resize(p.size());
            s.inlier.resize(p.size());
            std::size_t next[2] = {0, 0};
            for (std::size_t i = 0; i < p.size(); ++i) {
                const std::uint8_t c = f.cluster[i];
                const FitResiduals& r = c == 0 ? f.fit.first.fit : f.fit.second.fit;
                s.residuals[i] = r.residuals[next[c]];
                s.inlier[i] = r.inlier[next[c]];
                ++next[c];
            }
            s.fit_message = f.fit.message + "\n  first sphere: " + f.fit.first.fit.message +
                            "\n  second sphere: " + f.fit.second.fit.message;
            items = {mm("ballbar.length", "centre distance", f.length)};
            if (f.spacing_error)
                items.push_back(mm("ballbar.spacing_error",
                                   "sphere spacing error SD (measured - nominal)",
                                   *f.spacing_error));
            items.push_back(
                mm("ballbar.diameter_1", "diameter, first sphere", 2 * f.fit.first.radius));
            items.push_back(
                mm("ballbar.diameter_2", "diameter, second sphere", 2 * f.fit.second.radius));
            items.push_back(mm("ballbar.form_1", "form P_F, first sphere", f.form_first));
            items.push_back(mm("ballbar.form_2", "form P_F, second sphere", f.form_second));
            if (f.size_error_first) {
                items.push_back(
                    mm("ballbar.size_error_1", "size P_S, first sphere", *f.size_error_first));
                items.push_back(
                    mm("ballbar.size_error_2", "size P_S, second sphere", *f.size_error_second));
            }
            items.push_back(count("ballbar.points_1", "points, first sphere",
                                  f.fit.first.fit.residuals.size()));
            items.push_back(count("ballbar.points_2", "points, second sphere",
                                  f.fit.second.fit.residuals.size()));
        }
    } catch (const FitError& e) {
        throw InputError(s.path, "--fit " + shape, e.what());
    }
    residual_items(s, options);
}

// ---------------------------------------------------------------- truth

struct Truth {
    fs::path manifest;
    fs::path file;
    Image<float> xyz;
};

Truth load_truth(const fs::path& folder) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec))
        throw InputError(folder, "--truth", "is not a capture set folder");
    Truth t;
    t.manifest = folder / "capture.yaml";
    if (!fs::exists(t.manifest, ec))
        throw InputError(t.manifest, "", "no such file: --truth names a capture set folder");
    const CaptureManifest manifest = read_manifest(t.manifest);
    if (!manifest.truth || manifest.truth->xyz.empty())
        throw InputError(t.manifest, "truth.xyz",
                         "the capture set records no ground-truth XYZ (only simulated sets do)");
    t.file = folder / manifest.truth->xyz;
    t.xyz = read_tiff_float(t.file);
    if (t.xyz.channels() != 3)
        throw InputError(
            t.file, "", "expected 3 channels (X, Y, Z), found " + std::to_string(t.xyz.channels()));
    if (t.xyz.size() != manifest.camera)
        throw InputError(t.file, "",
                         "is " + report_size_text(t.xyz.size()) + ", but the camera is " +
                             report_size_text(manifest.camera));
    return t;
}

void compare_subject_with_truth(Subject& s, const Truth& truth) {
    require_organised(s, "the comparison against the ground truth");
    if (s.cloud.organised != truth.xyz.size())
        throw InputError(s.path, "obj_info organised_width/height",
                         "the cloud is organised " + report_size_text(s.cloud.organised) +
                             ", but the ground truth " + truth.file.string() + " is " +
                             report_size_text(truth.xyz.size()));
    s.truth = compare_with_truth(s.cloud, truth.xyz);
    const TruthComparison& t = *s.truth;
    s.truth_items = {
        count("truth.compared", "pixels compared", t.compared),
        {"truth.coverage", "coverage of the true surface", 100 * t.coverage, "%", 2},
        count("truth.no_surface", "points where the truth has no surface", t.no_surface),
        mm("truth.dz_mean", "Z error, mean (point - truth)", t.dz.mean),
        mm("truth.dz_rms", "Z error, RMS", t.dz.rms),
        mm("truth.dz_stddev", "Z error, standard deviation", t.dz.stddev),
        mm("truth.dz_max_abs", "Z error, largest magnitude", t.dz.max_abs),
        mm("truth.dz_shape_rms", "Z error less its offset and tilt, RMS", t.dz_shape.rms),
        mm("truth.distance_rms", "3D distance, RMS", t.distance.rms),
        mm("truth.distance_mean", "3D distance, mean", t.distance.mean),
        mm("truth.distance_max", "3D distance, largest", t.distance.max),
        mm("truth.rigid_distance_rms", "3D distance after one rigid motion of the whole cloud, RMS",
           t.distance_rigid.rms),
        mm("truth.rigid_distance_max",
           "3D distance after one rigid motion of the whole cloud, largest", t.distance_rigid.max),
        {"truth.rigid_angle", "that rigid motion's rotation",
         t.rigid_angle_rad * 180 / std::numbers::pi, "deg", 4},
        mm("truth.rigid_shift", "that rigid motion's translation",
           std::hypot(t.rigid_translation[0], t.rigid_translation[1], t.rigid_translation[2]))};
}

// ---------------------------------------------------------------- report

// A Markdown table of items with one value column per subject.
std::string item_table(const std::vector<const Subject*>& subjects,
                       std::vector<Item> Subject::*items) {
    std::ostringstream s;
    s << "| figure |";
    for (const Subject* subject : subjects)
        s << " " << subject->label << " |";
    s << " unit |\n|---|";
    for (std::size_t i = 0; i < subjects.size(); ++i)
        s << "---:|";
    s << "---|\n";
    for (const Item& item : subjects.front()->*items) {
        s << "| " << item.title << " |";
        for (const Subject* subject : subjects) {
            std::string text = "-";
            for (const Item& other : subject->*items)
                if (other.key == item.key)
                    text = value_text(other);
            s << " " << text << " |";
        }
        s << " " << item.unit << " |\n";
    }
    return s.str();
}

void add_items(std::vector<Figure>& figures, const Subject& s, const std::vector<Item>& items) {
    for (const Item& item : items)
        figures.push_back({s.prefix + "." + item.key, item.value, item.unit});
}

std::string fit_description(const std::string& shape) {
    if (shape == "plane")
        return "Least-squares plane (orthogonal distances); residual = signed distance, positive "
               "towards the camera. Flatness F as in VDI/VDE 2634 part 2: the residual range, "
               "also after excluding the 0.3 % of points the guideline allows to exclude.";
    const std::string common =
        "Least-squares geometric fit (orthogonal distances); residual = radial distance, "
        "positive outside.";
    if (shape == "sphere")
        return common + " Probing errors as in VDI/VDE 2634 part 2: form P_F = residual range "
                        "(also after excluding 0.3 % of the points), size P_S = fitted minus "
                        "calibrated diameter.";
    if (shape == "ball-bar")
        return common + " Sphere spacing error SD as in VDI/VDE 2634 part 2: measured minus "
                        "calibrated centre distance; the spheres are separated by 2-means "
                        "clustering.";
    return common;
}

struct Png {
    std::string name;
    cv::Mat image;
    std::string caption;
};

// ---------------------------------------------------------------- stages

// Arguments first: bad ones cost nothing and leave nothing behind.
void check_evaluate_arguments(const EvaluateArgs& args) {
    const fs::path out = args.out;
    {
        const fs::path target = out.filename().empty() ? out.parent_path() : out;
        const fs::path parent = target.parent_path();
        if (!parent.empty() && !fs::is_directory(parent))
            throw InputError(out, "--out", "the folder " + parent.string() + " does not exist");
        if (!report_folder_writable(target))
            throw InputError(out, "--out",
                             "exists and is not an earlier report (no summary.md); choose "
                             "another folder");
    }
    if (args.fit.empty() && args.truth.empty() && args.compare.empty())
        throw InputError("command line", "",
                         "nothing to evaluate: give --fit, --truth and/or --compare");
    const bool has_diameter = args.nominal_diameter_option->count() > 0;
    const bool has_length = args.nominal_length_option->count() > 0;
    if (has_diameter && (args.fit.empty() || args.fit == "plane"))
        throw InputError("command line", "--nominal-diameter",
                         "needs --fit sphere, cylinder or ball-bar");
    if (has_diameter && !(args.nominal_diameter > 0 && std::isfinite(args.nominal_diameter)))
        throw InputError("command line", "--nominal-diameter", "must be a positive length (mm)");
    if (has_length && args.fit != "ball-bar")
        throw InputError("command line", "--nominal-length", "needs --fit ball-bar");
    if (has_length && !(args.nominal_length > 0 && std::isfinite(args.nominal_length)))
        throw InputError("command line", "--nominal-length", "must be a positive length (mm)");
    if (!(args.reject_sigma == 0 || (args.reject_sigma >= 1 && std::isfinite(args.reject_sigma))))
        throw InputError("command line", "--reject-sigma", "must be 0 (off) or at least 1");
    if (args.compare.empty() && args.other_label_option->count())
        throw InputError("command line", "--other-label", "needs --compare");
    if (args.compare.empty() && args.match_option->count())
        throw InputError("command line", "--match", "needs --compare");
}

// CLOUD, and --compare's cloud (the two labels told apart by their paths
// when they are the same).
std::vector<Subject> load_subjects(const EvaluateArgs& args) {
    std::vector<Subject> subjects;
    const fs::path cloud_path = args.cloud;
    std::string label = args.label.empty() ? cloud_path.stem().string() : args.label;
    subjects.push_back(load_subject(cloud_path, label, "cloud"));
    if (!args.compare.empty()) {
        const fs::path other_path = args.compare;
        std::string other =
            args.other_label.empty() ? other_path.stem().string() : args.other_label;
        if (other == subjects[0].label) {
            subjects[0].label += " (" + cloud_path.string() + ")";
            other += " (" + other_path.string() + ")";
        }
        subjects.push_back(load_subject(other_path, other, "other"));
    }
    return subjects;
}

// Cloud to cloud (two subjects; nothing for one), checked before the
// (slower) fits.
std::optional<CloudDistance> compare_clouds(const std::vector<Subject>& subjects,
                                            const std::string& match) {
    std::optional<CloudDistance> distance;
    if (subjects.size() == 2) {
        const Subject& a = subjects[0];
        const Subject& b = subjects[1];
        if (match == "pixel") {
            for (const Subject& s : subjects)
                if (!s.cloud.is_organised())
                    throw InputError(s.path, "pixel",
                                     "the cloud has no camera pixel indices " +
                                         std::string(organised_hint) +
                                         "; --match pixel needs them (or use --match nearest)");
            if (a.cloud.organised != b.cloud.organised)
                throw InputError(b.path, "obj_info organised_width/height",
                                 "the cloud is organised " + report_size_text(b.cloud.organised) +
                                     ", but " + a.path.string() + " is " +
                                     report_size_text(a.cloud.organised) +
                                     ": a per-pixel comparison needs two reconstructions of "
                                     "the same camera");
            distance = compare_per_pixel(a.cloud, b.cloud);
        } else {
            distance = compare_nearest(a.cloud, b.cloud);
        }
    }
    return distance;
}

// The cloud-to-cloud figures ("compare." in figures.csv).
std::vector<Item> distance_items(const CloudDistance& d, const std::vector<const Subject*>& all) {
    std::vector<Item> compare_items;
    compare_items.push_back(count("matched", "points matched", d.matched));
    compare_items.push_back(count("only_cloud",
                                  d.per_pixel ? "pixels with a point of " + all[0]->label + " only"
                                              : "points of " + all[0]->label + " without a match",
                                  d.only_first));
    if (d.per_pixel) {
        compare_items.push_back(count(
            "only_other", "pixels with a point of " + all[1]->label + " only", d.only_second));
        compare_items.push_back(mm("dz_mean", "Z difference, mean", d.dz.mean));
        compare_items.push_back(mm("dz_rms", "Z difference, RMS", d.dz.rms));
        compare_items.push_back(mm("dz_stddev", "Z difference, standard deviation", d.dz.stddev));
    }
    compare_items.push_back(mm("distance_rms", "3D distance, RMS", d.distance.rms));
    compare_items.push_back(mm("distance_mean", "3D distance, mean", d.distance.mean));
    compare_items.push_back(mm("distance_max", "3D distance, largest", d.distance.max));
    return compare_items;
}

// figures.csv's rows: each cloud's figures, then the cloud-to-cloud ones.
std::vector<Figure> evaluation_figures(const std::vector<Subject>& subjects,
                                       const std::vector<Item>& compare_items) {
    std::vector<Figure> figures;
    for (const Subject& s : subjects) {
        figures.push_back({s.prefix + ".points", static_cast<double>(s.cloud.points.size()), ""});
        add_items(figures, s, s.fit_items);
        add_items(figures, s, s.truth_items);
    }
    for (const Item& item : compare_items)
        figures.push_back({"compare." + item.key, item.value, item.unit});
    return figures;
}

// A figure's limit, shared by the clouds so that their figures compare.
template <class ValuesOf>
double shared_limit(const std::vector<Subject>& subjects, ValuesOf values_of) {
    std::vector<double> values;
    for (const Subject& s : subjects) {
        const std::vector<double>& v = values_of(s);
        values.insert(values.end(), v.begin(), v.end());
    }
    return symmetric_limit(values, 0.995);
}

// fit-histogram.png and each cloud's fit map (a note instead for a cloud
// without pixel indices).
void add_fit_pngs(std::vector<Png>& pngs, std::string& notes, const std::vector<Subject>& subjects,
                  const std::string& shape) {
    const double limit = shared_limit(
        subjects, [](const Subject& s) -> const std::vector<double>& { return s.used_residuals; });
    std::vector<HistogramSeries> series;
    for (const Subject& s : subjects)
        series.push_back({s.label, s.used_residuals});
    const std::string sign = shape == "plane"
                                 ? "signed distance to the plane, + towards the camera (mm)"
                                 : "radial residual, + outside (mm)";
    pngs.push_back({"fit-histogram.png",
                    histogram_figure(series, -limit, limit, sign, shape + " fit residuals"),
                    "histogram of the " + shape + " fit residuals (used points)"});
    for (const Subject& s : subjects) {
        const std::string name =
            s.prefix == "cloud" ? "fit-map.png" : "fit-map-" + s.prefix + ".png";
        if (!s.cloud.is_organised()) {
            notes += "- no `" + name + "`: " + s.path.string() + " has no camera pixel indices\n";
            continue;
        }
        pngs.push_back(
            {name,
             signed_map_figure(values_image(s.cloud, s.residuals), limit,
                               s.label + ": " + shape + " fit residual, RMS " +
                                   fixed_text(error_stats(s.used_residuals).rms, 4) + " mm"),
             s.label + ": " + shape + " fit residual per camera pixel"});
    }
}

// truth-histogram.png and each cloud's truth map.
void add_truth_pngs(std::vector<Png>& pngs, const std::vector<Subject>& subjects) {
    const double limit = shared_limit(subjects, [](const Subject& s) -> const std::vector<double>& {
        return s.truth->dz_values;
    });
    std::vector<HistogramSeries> series;
    for (const Subject& s : subjects)
        series.push_back({s.label, s.truth->dz_values});
    pngs.push_back({"truth-histogram.png",
                    histogram_figure(series, -limit, limit, "Z error, point - truth (mm)",
                                     "error against the ground truth"),
                    "histogram of the Z error against the ground truth"});
    for (const Subject& s : subjects) {
        const std::string name =
            s.prefix == "cloud" ? "truth-map.png" : "truth-map-" + s.prefix + ".png";
        pngs.push_back({name,
                        signed_map_figure(s.truth->dz_map, limit,
                                          s.label +
                                              ": Z error against the ground truth, "
                                              "RMS " +
                                              fixed_text(s.truth->dz.rms, 4) + " mm"),
                        s.label + ": Z error against the ground truth per camera pixel"});
    }
}

// difference-histogram.png, and with per-pixel matching difference-map.png.
void add_difference_pngs(std::vector<Png>& pngs, const CloudDistance& distance,
                         const std::vector<const Subject*>& all) {
    const std::string pair = all[0]->label + " - " + all[1]->label;
    if (distance.per_pixel) {
        const double limit = symmetric_limit(distance.values, 0.995);
        pngs.push_back(
            {"difference-histogram.png",
             histogram_figure({{pair, distance.values}}, -limit, limit,
                              "Z difference per pixel (mm)", "cloud to cloud, same camera pixel"),
             "histogram of the Z difference " + pair + " per pixel"});
        pngs.push_back({"difference-map.png",
                        signed_map_figure(distance.dz_map, limit,
                                          pair + ": Z difference, RMS 3D distance " +
                                              fixed_text(distance.distance.rms, 4) + " mm"),
                        "Z difference " + pair + " per camera pixel"});
    } else {
        const double limit = symmetric_limit(distance.values, 0.995);
        pngs.push_back({"difference-histogram.png",
                        histogram_figure({{pair, distance.values}}, 0, limit,
                                         "distance to the nearest point (mm)",
                                         "cloud to cloud, nearest point"),
                        "histogram of the nearest-point distances " + pair});
    }
}

// summary.md's sections, in order.

void summary_clouds(std::ostream& md, const std::vector<Subject>& subjects) {
    md << "# Evaluation\n\n";
    for (const Subject& s : subjects)
        md << "- **" << s.label << "**: `" << s.path.string() << "`, " << s.cloud.points.size()
           << " points, "
           << (s.cloud.is_organised() ? "organised " + report_size_text(s.cloud.organised)
                                      : std::string("unorganised"))
           << "\n";
}

void summary_fit(std::ostream& md, const std::vector<Subject>& subjects,
                 const std::vector<const Subject*>& all, const std::string& shape) {
    md << "\n## " << shape << " fit\n\n"
       << fit_description(shape) << "\n\n"
       << item_table(all, &Subject::fit_items) << "\n";
    for (const Subject& s : subjects)
        md << "- " << s.label << ": " << s.fit_message << "\n";
}

void summary_truth(std::ostream& md, const Truth& truth, const std::vector<const Subject*>& all) {
    md << "\n## Ground truth\n\n`" << truth.file.string()
       << "`: per camera pixel, point minus true point (both on the pixel's ray).\n\n"
       << item_table(all, &Subject::truth_items);
}

void summary_distance(std::ostream& md, const CloudDistance& distance,
                      const std::vector<const Subject*>& all,
                      const std::vector<Item>& compare_items) {
    md << "\n## Cloud to cloud: " << all[0]->label << " - " << all[1]->label << "\n\n"
       << (distance.per_pixel ? "Per camera pixel where both clouds have a point.\n\n"
                              : "From each point of " + all[0]->label +
                                    " to the nearest point of " + all[1]->label + ".\n\n")
       << "| figure | value | unit |\n|---|---:|---|\n";
    for (const Item& item : compare_items)
        md << "| " << item.title << " | " << value_text(item) << " | " << item.unit << " |\n";
}

void summary_figure_list(std::ostream& md, const std::vector<Png>& pngs, const std::string& notes) {
    md << "\n## Figures\n\n";
    for (const Png& png : pngs)
        md << "- `" << png.name << "`: " << png.caption << "\n";
    md << notes;
}

int run_evaluate(const EvaluateArgs& args) {
    const fs::path out = args.out;
    check_evaluate_arguments(args);

    std::vector<Subject> subjects = load_subjects(args);
    std::vector<const Subject*> all;
    for (const Subject& s : subjects)
        all.push_back(&s);
    const std::optional<CloudDistance> distance = compare_clouds(subjects, args.match);
    std::optional<Truth> truth;
    if (!args.truth.empty()) {
        truth = load_truth(args.truth);
        for (Subject& s : subjects)
            compare_subject_with_truth(s, *truth);
    }
    if (!args.fit.empty())
        for (Subject& s : subjects)
            fit_subject(s, args.fit, args);

    std::vector<Item> compare_items;
    if (distance)
        compare_items = distance_items(*distance, all);
    const std::vector<Figure> figures = evaluation_figures(subjects, compare_items);

    std::vector<Png> pngs;
    std::string notes;
    if (!args.fit.empty())
        add_fit_pngs(pngs, notes, subjects, args.fit);
    if (truth)
        add_truth_pngs(pngs, subjects);
    if (distance)
        add_difference_pngs(pngs, *distance, all);

    std::ostringstream md;
    summary_clouds(md, subjects);
    if (!args.fit.empty())
        summary_fit(md, subjects, all, args.fit);
    if (truth)
        summary_truth(md, *truth, all);
    if (distance)
        summary_distance(md, *distance, all, compare_items);
    summary_figure_list(md, pngs, notes);
    const std::string summary = md.str();
    const std::string csv = figures_csv(figures);

    write_report_folder(out, [&](const fs::path& temp) {
        write_file_synced(temp / "summary.md", summary);
        write_file_synced(temp / "figures.csv", csv);
        for (const Png& png : pngs)
            save_png(temp / png.name, png.image);
    });
    std::cout << summary << "\nwrote " << out.string() << "\n";
    return 0;
}

} // namespace

Action add_evaluate_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<EvaluateArgs>(
        app, "evaluate",
        "Evaluate a reconstruction: shape fit figures (VDI/VDE 2634-2 style flatness, probing "
        "form and size, sphere spacing; cylinder), errors against a simulated capture's ground "
        "truth, distances to a second reconstruction; writes a report folder",
        run_evaluate);
    cmd->add_option("cloud", args->cloud, "point cloud to evaluate (.ply)")->required();
    cmd->add_option("--fit", args->fit,
                    "fit a shape to all points of the cloud (and of --compare's): plane, sphere, "
                    "cylinder, ball-bar (two spheres)")
        ->check(CLI::IsMember({"plane", "sphere", "cylinder", "ball-bar"}));
    args->nominal_diameter_option = cmd->add_option(
        "--nominal-diameter", args->nominal_diameter,
        "calibrated diameter (mm) of the sphere(s) or cylinder: adds the size error");
    args->nominal_length_option =
        cmd->add_option("--nominal-length", args->nominal_length,
                        "calibrated centre distance (mm) of the ball-bar: adds the sphere "
                        "spacing error");
    cmd->add_option("--reject-sigma", args->reject_sigma,
                    "reject points beyond K times the RMS residual, iteratively, before the "
                    "figures (0 = off)")
        ->capture_default_str();
    cmd->add_option("--truth", args->truth,
                    "simulated capture set folder whose capture.yaml lists truth.xyz: error per "
                    "camera pixel against it");
    cmd->add_option("--compare", args->compare,
                    "second reconstruction of the same scene and camera (.ply): the same "
                    "figures for it, and the distance between the two");
    args->match_option = cmd->add_option("--match", args->match,
                                         "how --compare pairs points: pixel (same camera pixel; "
                                         "organised clouds) or nearest (nearest point)")
                             ->check(CLI::IsMember({"pixel", "nearest"}))
                             ->capture_default_str();
    cmd->add_option("--label", args->label, "name of CLOUD in the report (default: file name)");
    args->other_label_option = cmd->add_option("--other-label", args->other_label,
                                               "name of --compare's cloud in the report");
    cmd->add_option("--out", args->out,
                    "report folder to write (must not exist, be empty, or hold an earlier "
                    "report, which is replaced)")
        ->required();
    return action;
}

} // namespace fpp::calib
