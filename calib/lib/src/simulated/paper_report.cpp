// The paper experiments' targets and report/summary.md (see paper_run.hpp).

#include "fpp/calib/plots.hpp"
#include "fpp/enum_names.hpp"
#include "paper_run.hpp"

#include <cmath>
#include <sstream>

namespace fpp::calib::paper {

namespace {

void row(std::ostream& md, const std::vector<std::string>& cells) {
    md << "|";
    for (const std::string& c : cells)
        md << " " << c << " |";
    md << "\n";
}

void header(std::ostream& md, const std::vector<std::string>& cells) {
    row(md, cells);
    std::vector<std::string> align{"---"};
    align.resize(cells.size(), "---:");
    row(md, align);
}

std::string mm(double v, int digits = 4) {
    return fixed_text(v, digits);
}

// The largest |value| over the ball bars' positions for a method.
double largest_spacing_error(const Record& r, std::size_t m, bool noisy) {
    double worst = 0;
    for (const BallBarPosition& b : r.ball_bars) {
        const double e = noisy ? b.spacing_error[m] : b.spacing_error_clean[m];
        if (!std::isfinite(e))
            return kNaN;
        worst = std::max(worst, std::fabs(e));
    }
    return r.ball_bars.empty() ? kNaN : worst;
}

double largest_size_error(const Record& r, std::size_t m) {
    double worst = 0;
    for (const BallBarPosition& b : r.ball_bars)
        worst = std::isfinite(b.size_error[m]) ? std::max(worst, b.size_error[m]) : kNaN;
    return r.ball_bars.empty() ? kNaN : worst;
}

const char* kAbsoluteScans[] = {"plane", "cylinder", "sphere", "relief"};

// Frame turns above this get their own table of errors (0.1 mrad: 0.05 mm
// sideways at 500 mm).
constexpr double kReportedTurnRad = 1e-4;

// `first` followed by the absolute scans the run has.
std::vector<std::string> with_absolute_scans(const Record& r, std::vector<std::string> first) {
    for (const char* key : kAbsoluteScans)
        if (r.scan(key))
            first.push_back(key);
    return first;
}

// A method's name, bold for the default one.
std::string method_cell(const Record& r, std::size_t m, std::size_t best) {
    return m == best ? "**" + r.methods[m].key + "**" : r.methods[m].key;
}

// Method m's "RMS / mean" of `errors` (one of ScanSummary's per-method Z
// errors) on each absolute scan the run has.
void add_absolute_errors(const Record& r, std::size_t m,
                         std::vector<ErrorStats> ScanSummary::*errors,
                         std::vector<std::string>& cells) {
    for (const char* key : kAbsoluteScans)
        if (const ScanSummary* s = r.scan(key))
            cells.push_back(mm((s->*errors)[m].rms) + " / " + mm((s->*errors)[m].mean));
}

} // namespace

constexpr EnumName<Procedure> kProcedureNames[] = {
    {Procedure::reference, "reference"},
    {Procedure::paper, "paper"},
    {Procedure::planes, "planes"},
    {Procedure::boards, "boards"},
};

const char* procedure_title(Procedure p) {
    return name_of(kProcedureNames, p);
}

std::string seconds_text(double s) {
    if (!std::isfinite(s))
        return "-";
    if (s >= 1)
        return fixed_text(s, 3) + " s";
    if (s >= 1e-3)
        return fixed_text(s * 1e3, 2) + " ms";
    return fixed_text(s * 1e6, 1) + " us";
}

std::size_t Record::find(const std::string& key) const {
    for (std::size_t m = 0; m < methods.size(); ++m)
        if (methods[m].key == key)
            return m;
    return methods.size();
}

const FrameTurn* Record::turn_of(Procedure p) const {
    switch (p) {
    case Procedure::reference:
        return nullptr;
    case Procedure::paper:
        return &paper_turn;
    case Procedure::planes:
    case Procedure::boards:
        return &our_turn;
    }
    return nullptr;
}

const ScanSummary* Record::scan(const std::string& key) const {
    for (const ScanSummary& s : scans)
        if (s.key == key)
            return &s;
    return nullptr;
}

std::size_t Record::default_method() const {
    for (std::size_t m = 0; m < methods.size(); ++m)
        if (methods[m].is_default)
            return m;
    return 0;
}

namespace {

// Adds a target to `targets`.
struct TargetList {
    std::vector<PaperTarget>& targets;
    void operator()(const std::string& key, const std::string& description, bool met,
                    const std::string& detail) const {
        targets.push_back({key, description, met, detail});
    }
};

// The default method's: its absolute accuracy, diameters, ball bar and
// calibration time.
void add_default_method_targets(std::vector<PaperTarget>& targets, const Record& r) {
    const TargetList target{targets};
    const std::size_t exact = r.find("exact");
    const std::size_t best = r.default_method();
    const std::size_t paper_rational = r.find("paper-rational");
    const std::string best_key = r.methods[best].key;

    // Absolute accuracy of the default method: nothing removed.
    for (const char* key : kAbsoluteScans) {
        const ScanSummary* s = r.scan(key);
        if (!s)
            continue;
        for (const bool clean : {true, false}) {
            const ErrorStats& e = clean ? s->truth_clean[best] : s->truth_noisy[best];
            const ErrorStats& floor = clean ? s->truth_clean[exact] : s->truth_noisy[exact];
            const double bound = clean ? kTruthRmsNoiseFree : kTruthRmsNoisy;
            const std::string noise = clean ? "noise_free" : "noisy";
            const std::string noise_text = clean ? "noise-free" : "with noise";
            target(std::string(key) + ".truth_rms." + noise + "." + best_key,
                   std::string(key) + ": " + best_key + " Z error vs truth, all of it, <= " +
                       mm(bound, 3) + " mm RMS (" + noise_text + ")",
                   e.rms <= bound,
                   mm(e.rms, 5) + " mm (the rig's exact model: " + mm(floor.rms, 5) + " mm)");
            target(std::string(key) + ".truth_bias." + noise + "." + best_key,
                   std::string(key) + ": " + best_key + " mean Z error (bias) within " +
                       mm(kTruthBias, 3) + " mm (" + noise_text + ")",
                   std::fabs(e.mean) <= kTruthBias,
                   mm(e.mean, 5) + " mm (the rig's exact model: " + mm(floor.mean, 5) + " mm)");
        }
        if (paper_rational < r.methods.size())
            target(std::string(key) + ".better_than_paper." + best_key,
                   std::string(key) + ": " + best_key +
                       " Z error vs truth <= the paper's procedure's (rational, noise-free)",
                   s->truth_clean[best].rms <= s->truth_clean[paper_rational].rms,
                   mm(s->truth_clean[best].rms, 5) + " mm vs " +
                       mm(s->truth_clean[paper_rational].rms, 5) + " mm");
    }
    for (const auto& [key, nominal] :
         {std::pair{"cylinder", kCylinderDiameter}, std::pair{"sphere", kSphereDiameter}}) {
        const ScanSummary* s = r.scan(key);
        if (!s || s->diameter_error.empty())
            continue;
        const double e = s->diameter_error[best];
        target(std::string(key) + ".diameter." + best_key,
               std::string(key) + ": " + best_key + " diameter within " + mm(kDiameterError, 3) +
                   " mm of " + fixed_text(nominal, 0) + " mm (with noise)",
               std::fabs(e) <= kDiameterError,
               mm(e, 5) + " mm (the rig's exact model: " + mm(s->diameter_error[exact], 5) +
                   " mm)");
    }
    if (!r.ball_bars.empty()) {
        const double worst = largest_spacing_error(r, best, true);
        target("ball_bar.spacing_error." + best_key,
               "ball bar, 7 places: " + best_key + " sphere-spacing error at most " +
                   mm(kBallBarSpacingError, 3) + " mm everywhere (with noise)",
               worst <= kBallBarSpacingError,
               "largest " + mm(worst, 5) + " mm (the rig's exact model: " +
                   mm(largest_spacing_error(r, exact, true), 5) + " mm)");
    }
    if (r.options.binning == 1 && r.our_stereo.calibrated) {
        const double seconds = r.our_stereo.seconds + r.seconds_boards_hybrid;
        target("calibration_time." + best_key,
               "calibration from " + std::to_string(r.options.board_poses) +
                   " full-size poses (stereo and every table model) under " +
                   fixed_text(kCalibrationSeconds, 0) + " s",
               seconds <= kCalibrationSeconds,
               fixed_text(seconds, 1) + " s (stereo " + fixed_text(r.our_stereo.seconds, 1) +
                   " s, hybrid " + fixed_text(r.seconds_boards_hybrid, 1) + " s)");
    }
}

// The paper's relations, for its own procedure's tables.
void add_paper_relation_targets(std::vector<PaperTarget>& targets, const Record& r) {
    const TargetList target{targets};
    const std::size_t sv = r.find("sv-paper");
    for (std::size_t m = 0; m < r.methods.size(); ++m) {
        const Method& method = r.methods[m];
        if (method.procedure != Procedure::paper || !method.is_table())
            continue;
        for (const bool clean : {true, false}) {
            const std::string noise = clean ? "noise_free" : "noisy";
            const std::string noise_text = clean ? "noise-free" : "with noise";
            for (const char* key : kAbsoluteScans) {
                const ScanSummary* s = r.scan(key);
                if (!s)
                    continue;
                const bool plane = std::string(key) == "plane";
                const double factor = plane ? kPlaneRatioTarget : 1.0;
                const std::string relation = plane ? "<= 0.5 x SV's" : "<= SV's";
                const ErrorStats& a = clean ? s->truth_clean[m] : s->truth_noisy[m];
                const ErrorStats& b = clean ? s->truth_clean[sv] : s->truth_noisy[sv];
                target(std::string(key) + (plane ? "_half_of_sv." : "_no_worse_than_sv.") + noise +
                           "." + method.key,
                       std::string(key) + ": " + method.key + " Z error vs truth " + relation +
                           " (" + noise_text + ")",
                       a.rms <= factor * b.rms,
                       mm(a.rms, 5) + " mm vs " + (plane ? "0.5 x " : "") + mm(b.rms, 5) + " mm");
                const ErrorStats& as = clean ? s->shape_clean[m] : s->shape_noisy[m];
                const ErrorStats& bs = clean ? s->shape_clean[sv] : s->shape_noisy[sv];
                target(std::string(key) +
                           (plane ? "_shape_half_of_sv." : "_shape_no_worse_than_sv.") + noise +
                           "." + method.key,
                       std::string(key) + ": " + method.key +
                           " Z error shape vs truth (offset and tilt removed) " + relation + " (" +
                           noise_text + ")",
                       as.rms <= factor * bs.rms,
                       mm(as.rms, 5) + " mm vs " + (plane ? "0.5 x " : "") + mm(bs.rms, 5) + " mm");
            }
        }
        const ReliefSummary& relief = r.relief;
        if (m < relief.seconds.size() && std::isfinite(relief.seconds[m])) {
            const double speedup = relief.seconds[sv] / relief.seconds[m];
            target("relief_speedup_50x." + method.key,
                   "relief: " + method.key +
                       " reconstruction at least 50x faster than the paper's SV (one thread each)",
                   speedup >= kSpeedupTarget,
                   fixed_text(speedup, 1) + "x (" + seconds_text(relief.seconds[sv]) + " vs " +
                       seconds_text(relief.seconds[m]) + "; " +
                       fixed_text(relief.seconds_sv_plane_iteration / relief.seconds[m], 1) +
                       "x against the paper's plane iteration)");
        }
    }
}

} // namespace

std::vector<PaperTarget> evaluate_targets(const Record& r) {
    std::vector<PaperTarget> targets;
    add_default_method_targets(targets, r);
    add_paper_relation_targets(targets, r);
    return targets;
}

namespace {

// summary.md's sections, in order.

void introduction_section(std::ostream& md, const Record& r) {
    const PaperExperimentOptions& o = r.options;
    const std::size_t best = r.default_method();
    md << "# The paper's experiments on the virtual scanner\n\n";
    md << "Rig `" << r.rig.name << "` with its effects, camera " << r.rig.camera_size.width << " x "
       << r.rig.camera_size.height << " (binning " << o.binning << "), seed " << o.seed
       << ". Sessions: the paper's "
       << (o.sv_calibration == SvCalibrationSource::checkerboard
               ? std::to_string(o.checkerboard_poses) +
                     " checkerboard poses (its stereo calibration) and "
               : std::string())
       << o.plane_poses << " flat-board poses (gray-x), and our " << o.board_poses
       << " checkerboard poses (gray-xy, a 180 x 135 mm pattern on a 420 x 375 mm white board) "
          "for our stereo calibration and tables alike. Scans use gray-x; SV reconstructs with "
          "the projector column only.\n\n";
    md << "Methods, by procedure: **reference**, SV with the rig's exact model (what the scan's "
          "noise and decoding leave: no calibration does better); **paper**, the paper's joint "
          "stereo calibration and its hybrid tables from flat boards placed by that SV; "
          "**boards**, ours: one checkerboard session gives the camera-first stereo "
          "calibration with correction grids and the tables, each board placed by the camera "
          "alone (the default: `"
       << r.methods[best].key
       << "`); **planes**, our calibration with the paper's flat boards.\n\n";
    md << "Errors against the truth are per pixel in the camera frame, Z(point) - Z(true) "
          "along the pixel's ray, nothing removed first (no offset, no tilt); the shape RMS "
          "beside them is the same error less its own best a + b X + c Y. They use the pixels "
          "where every method gives a point (`boards-only-rational`, which covers less, on "
          "those of them where it has one), at least "
       << kEdgeMarginPx
       << " px inside the edge of that region (silhouette pixels mix the surface's phase with "
          "their neighbours').\n\n";
}

void noise_free_errors_table(std::ostream& md, const Record& r) {
    const std::size_t best = r.default_method();
    md << "Noise-free scans (each method's own error), Z error RMS / mean (bias), mm:\n\n";
    std::vector<std::string> head = with_absolute_scans(r, {"method", "procedure"});
    head.insert(head.end(), {"ball bar, largest SD error", "plane shape RMS"});
    header(md, head);
    for (std::size_t m = 0; m < r.methods.size(); ++m) {
        std::vector<std::string> cells{method_cell(r, m, best),
                                       procedure_title(r.methods[m].procedure)};
        add_absolute_errors(r, m, &ScanSummary::truth_clean, cells);
        cells.push_back(mm(largest_spacing_error(r, m, false)));
        const ScanSummary* plane = r.scan("plane");
        cells.push_back(plane ? mm(plane->shape_clean[m].rms) : "-");
        row(md, cells);
    }
}

// The camera frame's turn: reported beside the errors above, which keep it
// (frame_turn.hpp).
void frame_turn_paragraph(std::ostream& md, const Record& r) {
    const std::size_t best = r.default_method();
    const double turn = std::max(r.paper_turn.angle_rad, r.our_turn.angle_rad);
    md << "\nEach calibration's camera frame against the rig's, measured from the camera's "
          "rays alone: ours turned by "
       << fixed_text(1000 * r.our_turn.angle_rad, 3) << " mrad (rays then "
       << fixed_text(1e6 * r.our_turn.ray_rms_rad, 1) << " urad RMS apart), the paper's by "
       << fixed_text(1000 * r.paper_turn.angle_rad, 3)
       << " mrad. A camera defect outside the "
          "calibration's model can move the image as a turn of the camera does; no board "
          "tells the two apart, and the calibration holds the rig turned about the camera "
          "centre with its shapes and lengths intact.";
    if (turn > kReportedTurnRad) {
        md << " The same noise-free errors with each calibration's points turned back by "
              "its frame's turn (beside the errors above, not instead of them), Z error RMS "
              "/ mean, mm:\n\n";
        header(md, with_absolute_scans(r, {"method"}));
        for (std::size_t m = 0; m < r.methods.size(); ++m) {
            std::vector<std::string> cells{method_cell(r, m, best)};
            add_absolute_errors(r, m, &ScanSummary::turned_clean, cells);
            row(md, cells);
        }
    } else {
        md << " Here the turns are too small to matter.\n";
    }
}

void noisy_errors_table(std::ostream& md, const Record& r) {
    const std::size_t best = r.default_method();
    md << "\nWith the rig's noise (one scan each), Z error RMS / mean, mm; diameters and the "
          "ball bar fitted to the noisy points:\n\n";
    std::vector<std::string> head = with_absolute_scans(r, {"method"});
    head.insert(head.end(), {"cylinder diameter error", "sphere diameter error",
                             "ball bar, largest SD error", "ball, largest size error"});
    header(md, head);
    for (std::size_t m = 0; m < r.methods.size(); ++m) {
        std::vector<std::string> cells{method_cell(r, m, best)};
        add_absolute_errors(r, m, &ScanSummary::truth_noisy, cells);
        for (const char* key : {"cylinder", "sphere"}) {
            const ScanSummary* s = r.scan(key);
            cells.push_back(s && !s->diameter_error.empty() ? mm(s->diameter_error[m]) : "-");
        }
        cells.push_back(mm(largest_spacing_error(r, m, true)));
        cells.push_back(mm(largest_size_error(r, m)));
        row(md, cells);
    }
}

void truth_errors_section(std::ostream& md, const Record& r) {
    md << "## Errors against the truth\n\n";
    noise_free_errors_table(md, r);
    frame_turn_paragraph(md, r);
    noisy_errors_table(md, r);
    md << "\nThe `exact` row is the floor: the error of each scan's own noise and decoding. "
          "Where a target with noise is not met by `"
       << r.methods[r.default_method()].key
       << "` but the floor is close to it, the scan's noise, not the calibration, is what is "
          "left.\n\n";
}

void paper_figures_section(std::ostream& md, const Record& r) {
    const std::size_t best = r.default_method();
    md << "## The paper's figures beside ours\n\n";
    const std::size_t paper_sv = r.find("sv-paper"), poly = r.find("paper-polynomial"),
                      rational = r.find("paper-rational");
    header(md,
           {"figure", "paper SV", "paper hybrid", "our SV of the paper's procedure",
            "its rational table", "its polynomial table", "ours (" + r.methods[best].key + ")"});
    const auto fit = [&](const char* key, std::size_t m) {
        const ScanSummary* s = r.scan(key);
        return s && m < s->fit_rms.size() ? mm(s->fit_rms[m]) : std::string("-");
    };
    row(md,
        {"plane-fit RMS, inclined plane (mm)", mm(kPaperPlaneSv, 3), mm(kPaperPlaneHybrid, 3),
         fit("plane", paper_sv), fit("plane", rational), fit("plane", poly), fit("plane", best)});
    row(md, {"cylinder-fit RMS (mm)", mm(kPaperCylinderSv, 3), mm(kPaperCylinderHybrid, 3),
             fit("cylinder", paper_sv), fit("cylinder", rational), fit("cylinder", poly),
             fit("cylinder", best)});
    const ReliefSummary& relief = r.relief;
    const auto time = [&](std::size_t m) {
        return m < relief.seconds.size() ? seconds_text(relief.seconds[m]) : std::string("-");
    };
    row(md, {"relief reconstruction time (one thread)", seconds_text(kPaperReliefSvSeconds),
             seconds_text(kPaperReliefHybridSeconds), time(paper_sv), time(rational), time(poly),
             time(best)});
    const auto distance = [&](std::size_t m) {
        for (std::size_t k = 0; k < relief.compared_methods.size(); ++k)
            if (relief.compared_methods[k] == m)
                return mm(relief.distance_rms[k]);
        return std::string("-");
    };
    row(md, {"relief: RMS distance SV vs hybrid (mm)", "-", mm(kPaperReliefDistance, 3), "-",
             distance(rational), distance(poly), "-"});
    md << "\nThe paper's times are of its implementation on its authors' PC; ours of this "
          "build on this machine. SV uses our Newton solver; the paper's plane iteration "
          "took "
       << seconds_text(relief.seconds_sv_plane_iteration) << ".\n\n";
}

void calibration_section(std::ostream& md, const Record& r) {
    md << "## Calibration\n\n";
    header(md, {"stereo calibration", "procedure", "poses", "camera RMS (px)", "projector RMS (px)",
                "dense samples RMS (px)", "correction grids, largest (px)", "time"});
    for (const auto& [name, s] : {std::pair{"the paper's (`calib-paper.yaml`)", &r.paper_stereo},
                                  std::pair{"ours (`calib.yaml`)", &r.our_stereo}}) {
        if (!s->calibrated) {
            row(md, {name, "the rig's 5-coefficient model", "-", "-", "-", "-", "-", "-"});
            continue;
        }
        row(md,
            {name, s->procedure, std::to_string(s->poses), mm(s->camera_rms), mm(s->projector_rms),
             s->dense_rms >= 0 ? mm(s->dense_rms) : "-",
             "camera " + mm(s->camera_grid_max, 3) + ", projector " + mm(s->projector_grid_max, 3),
             seconds_text(s->seconds)});
    }
    if (r.our_stereo.calibrated)
        md << "\nOur camera grid's smoothness, chosen by cross-validation over the poses: "
           << fixed_text(r.our_stereo.camera_grid_smoothness, 0)
           << ". Reports: `stereo-report/`, `stereo-report-paper/`.\n\n";
    header(md, {"table", "poses used", "pixels modelled", "median Z fit RMS (mm)",
                "median predicted depth sigma (mm)", "time"});
    for (const Method& m : r.methods)
        if (m.is_table())
            row(md, {m.key, std::to_string(m.usable_poses) + " / " + std::to_string(m.poses),
                     std::to_string(m.pixels_modelled) + " / " +
                         std::to_string(r.rig.camera_size.area()),
                     mm(m.fit_rms_z_median), mm(m.sigma_z_median), seconds_text(m.seconds)});
    md << "\nOur procedure from its session: stereo " << seconds_text(r.our_stereo.seconds)
       << ", hybrid (all three models) " << seconds_text(r.seconds_boards_hybrid)
       << ". Tables: `table-<method>.fpt`; reports: `hybrid-report-<method>/`.\n\n";
}

void scan_section(std::ostream& md, const Record& r, const ScanSummary& s) {
    md << "## " << s.title << "\n\n";
    if (s.key == "relief")
        md << "Relief scaled by " << fixed_text(r.relief.scale, 3) << ", seen by "
           << r.relief.pixels_seen << " lit camera pixels.\n\n";
    md << "Pixels with a true surface: " << s.truth_pixels
       << "; compared (a point from every method, " << kEdgeMarginPx
       << " px inside the edge): " << s.common << ".\n\n";
    const bool fitted = s.fit != FitKind::none;
    const bool round = s.fit == FitKind::cylinder || s.fit == FitKind::sphere;
    std::vector<std::string> head{"method", "points"};
    if (fitted)
        head.insert(head.end(), {"fit RMS (mm)", "fit RMS, noise-free (mm)"});
    if (round)
        head.insert(head.end(), {"diameter (mm)", "diameter error (mm)"});
    head.insert(head.end(),
                {"Z error RMS (mm)", "Z error RMS, noise-free (mm)", "mean (bias), noise-free (mm)",
                 "shape RMS, noise-free (mm)", "3D distance RMS, noise-free (mm)"});
    header(md, head);
    for (std::size_t m = 0; m < r.methods.size(); ++m) {
        std::vector<std::string> cells{r.methods[m].key, std::to_string(s.points[m])};
        if (fitted)
            cells.insert(cells.end(), {mm(s.fit_rms[m]), mm(s.fit_rms_clean[m])});
        if (round)
            cells.insert(cells.end(), {mm(s.diameter[m], 3), mm(s.diameter_error[m])});
        cells.insert(cells.end(),
                     {mm(s.truth_noisy[m].rms), mm(s.truth_clean[m].rms), mm(s.truth_clean[m].mean),
                      mm(s.shape_clean[m].rms), mm(s.distance_clean[m].rms)});
        row(md, cells);
    }
    if (!s.fit_note.empty())
        md << "\n" << s.fit_note << "\n";
    md << "\nFigures: ";
    if (fitted)
        md << "`" << s.key << "-fit-histogram.png`, `" << s.key << "-fit-map-<method>.png`, ";
    md << "`truth-" << s.key << "-<method>.png` (noise-free Z error maps).\n\n";
}

void ball_bar_section(std::ostream& md, const Record& r) {
    const std::size_t best = r.default_method();
    const std::size_t exact = r.find("exact");
    md << "## Ball bar (ours): two " << fixed_text(kBallDiameter, 0) << " mm spheres "
       << fixed_text(kBallBarLength, 0)
       << " mm apart at seven places and directions\n\n"
          "Sphere-spacing error (VDI/VDE 2634-2 SD: measured minus true centre distance, "
          "mm), with noise / noise-free:\n\n";
    std::vector<std::string> head{"centre (mm)", "direction"};
    std::vector<std::size_t> shown;
    for (std::size_t m = 0; m < r.methods.size(); ++m)
        if (m == exact || m == best || r.methods[m].key == "sv-paper" ||
            r.methods[m].key == "paper-rational" || r.methods[m].key == "sv" ||
            r.methods[m].key == "planes-rational") {
            shown.push_back(m);
            head.push_back(r.methods[m].key);
        }
    header(md, head);
    for (const BallBarPosition& b : r.ball_bars) {
        std::vector<std::string> cells{fixed_text(b.centre[0], 0) + ", " +
                                           fixed_text(b.centre[1], 0) + ", " +
                                           fixed_text(b.centre[2], 0),
                                       fixed_text(b.axis[0], 2) + ", " + fixed_text(b.axis[1], 2) +
                                           ", " + fixed_text(b.axis[2], 2)};
        for (const std::size_t m : shown)
            cells.push_back(mm(b.spacing_error[m]) + " / " + mm(b.spacing_error_clean[m]));
        row(md, cells);
    }
    md << "\nEvery method's figures: `figures.csv` (`ball_bar.<place>.<method>.*`).\n\n";
}

void relief_comparison_section(std::ostream& md, const Record& r) {
    md << "## Experiment 3: the paper's SV against its tables on the relief\n\n";
    header(md, {"SV vs", "pixels", "RMS 3D distance (mm)", "RMS Z difference (mm)",
                "time, one thread", "speed-up over SV"});
    const std::size_t sv = r.find("sv-paper");
    for (std::size_t k = 0; k < r.relief.compared_methods.size(); ++k) {
        const std::size_t m = r.relief.compared_methods[k];
        row(md,
            {r.methods[m].key, std::to_string(r.relief.matched[k]), mm(r.relief.distance_rms[k]),
             mm(r.relief.dz_rms[k]), seconds_text(r.relief.seconds[m]),
             fixed_text(r.relief.seconds[sv] / r.relief.seconds[m], 1) + "x"});
    }
    md << "\n";
}

void windows_section(std::ostream& md, const Record& r) {
    md << "## Experiment 4: N x N windows of the plane scan\n\n";
    md << "SV runs on the cropped camera (principal point shifted), the kernel on the "
          "cropped table; both give the full image's points to "
       << fixed_text(r.windows.crop_max_difference_mm * 1e3, 3) << " um ("
       << r.windows.crop_mismatched << " pixels with a point in one only).\n\n";
    std::vector<std::string> head{"N", "SV points"};
    for (const std::size_t m : r.windows.methods)
        head.push_back(r.methods[m].key);
    header(md, head);
    for (std::size_t w = 0; w < r.windows.sizes.size(); ++w) {
        std::vector<std::string> cells{std::to_string(r.windows.sizes[w]),
                                       std::to_string(r.windows.points[w])};
        for (std::size_t k = 0; k < r.windows.methods.size(); ++k)
            cells.push_back(seconds_text(r.windows.seconds[k][w]));
        row(md, cells);
    }
    md << "\nFigure: `windows-timing.png`.\n\n";
}

void targets_section(std::ostream& md, const std::vector<PaperTarget>& targets) {
    md << "## Targets\n\n";
    header(md, {"target", "met", "numbers"});
    for (const PaperTarget& t : targets)
        row(md, {t.description, t.met ? "yes" : "**no**", t.detail});
    md << "\nAll figures: `figures.csv` (name,value,unit).\n";
}

} // namespace

std::string summary_markdown(const Record& r, const std::vector<PaperTarget>& targets) {
    std::ostringstream md;
    introduction_section(md, r);
    truth_errors_section(md, r);
    paper_figures_section(md, r);
    calibration_section(md, r);
    for (const ScanSummary& s : r.scans)
        scan_section(md, r, s);
    if (!r.ball_bars.empty())
        ball_bar_section(md, r);
    if (!r.relief.compared_methods.empty())
        relief_comparison_section(md, r);
    windows_section(md, r);
    targets_section(md, targets);
    return md.str();
}

} // namespace fpp::calib::paper
