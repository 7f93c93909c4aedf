#include "correct_report.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/calib/plots.hpp"
#include "fpp/calib/report_folder.hpp"

#include <cmath>
#include <sstream>

namespace fpp::calib {

namespace {

// Largest |value| of a figure, or NaN when the record lacks it.
double worst_of(const VerificationRecord& r, const std::string& name) {
    for (const FigureVerdict& f : r.figures)
        if (f.name == name)
            return f.worst;
    return std::nan("");
}

std::string signed_mm(double value) {
    return (value >= 0 ? "+" : "") + fixed_text(value, 4);
}

void held_out_table(std::ostringstream& s, const VerificationRecord& before,
                    const VerificationRecord& after) {
    s << "| position | SD before (mm) | SD after (mm) | largest P_F before / after (mm) | "
         "largest |P_S| before / after (mm) |\n|---|---|---|---|---|\n";
    for (std::size_t k = 0; k < before.positions.size() && k < after.positions.size(); ++k) {
        const MeasuredPosition& b = before.positions[k];
        const MeasuredPosition& a = after.positions[k];
        double pf[2] = {0, 0}, ps[2] = {0, 0};
        for (const MeasuredSphere& sphere : b.spheres) {
            pf[0] = std::max(pf[0], sphere.form);
            ps[0] = std::max(ps[0], std::abs(sphere.size_error));
        }
        for (const MeasuredSphere& sphere : a.spheres) {
            pf[1] = std::max(pf[1], sphere.form);
            ps[1] = std::max(ps[1], std::abs(sphere.size_error));
        }
        s << "| " << b.capture.string() << " | " << signed_mm(b.spacing_error.value_or(0)) << " | "
          << signed_mm(a.spacing_error.value_or(0)) << " | " << fixed_text(pf[0], 4) << " / "
          << fixed_text(pf[1], 4) << " | " << fixed_text(ps[0], 4) << " / " << fixed_text(ps[1], 4)
          << " |\n";
    }
    s << "\n";
    bool worse = false;
    for (const char* name : {"SD", "P_F", "P_S"}) {
        const double was = worst_of(before, name), is = worst_of(after, name);
        s << "- " << name << " worst |value|: " << fixed_text(was, 4) << " mm before, "
          << fixed_text(is, 4) << " mm after";
        // 1 um of slack: the same clouds measured through two tables differ
        // by about that in sphere fits even where nothing changed.
        if (is > was + 0.001) {
            s << " — **worse after the correction**";
            worse = true;
        }
        s << "\n";
    }
    s << "\n"
      << (worse ? "A held-out figure got worse: check the artefact, the captures and the "
                  "session before using the corrected calibration.\n"
                : "No held-out figure got worse.\n");
}

} // namespace

std::string correction_summary(const CorrectionRecord& r) {
    std::ostringstream s;
    s << "# Depth-scale correction with a certified artefact\n\n"
      << "- artefact: " << r.artefact.string() << "\n- calibration: " << r.calibration.string()
      << "\n- session: " << r.session.string() << "\n- table: " << r.table.string()
      << "\n- written: " << r.out_calibration.string() << ", " << r.out_table.string()
      << "\n- used positions:";
    for (const std::filesystem::path& p : r.used)
        s << " " << p.string();
    s << "\n\n## Rounds\n\n"
      << "Each round measures the used positions with a table and fits the depth scale k "
         "(the lengths |(d_x, d_y, k d_z)| against the certificate); the next calibration "
         "is the session's, camera first, with the camera's focal lengths scaled by the "
         "product of the corrections so far.\n\n"
      << "| round | camera focal scale | SD of the used positions (mm) | k - 1 (ppm) | sigma "
         "(ppm) | scatter after the fit (mm) |\n|---|---|---|---|---|---|\n";
    for (std::size_t i = 0; i < r.rounds.size(); ++i) {
        const CorrectionRound& round = r.rounds[i];
        s << "| " << i << (i == 0 ? " (input)" : "") << " | "
          << fixed_text(round.camera_focal_scale, 6) << " |";
        for (double sd : round.fit.before_mm)
            s << " " << signed_mm(sd);
        s << " | " << fixed_text(round.fit.correction_ppm(), 0) << " | "
          << fixed_text(round.fit.sigma * 1e6, 0) << " | " << fixed_text(round.fit.scatter_mm, 4)
          << " |\n";
    }
    s << "\n"
      << (r.converged ? "The last round's correction is within its noise (2 sigma)."
                      : "**The last round's correction is still above its noise** (3 rounds "
                        "at most): the written calibration has the remaining error.")
      << " Camera focal scale written: " << fixed_text(r.final_focal_scale, 6) << ".\n\n"
      << "## Trueness\n\nPredicted by the input calibration: " << trueness_summary(r.predicted)
      << "\nWritten with the corrected calibration: along depth from the artefact fit of the "
         "last round (the sigma of k: the certificate's uncertainty and the scatter of the "
         "used positions' lengths after the fit, times the length), across as the "
         "calibration predicts: "
      << trueness_summary(r.corrected) << "\n";
    if (r.before && r.after) {
        s << "## Held-out positions (never used for the correction)\n\n";
        held_out_table(s, *r.before, *r.after);
        s << "\nIn full: before/verification.json (the input table), "
             "after/verification.json (the corrected table).\n";
    } else {
        s << "## Held-out positions\n\nNone given (--held-out): the correction is not "
             "verified on positions it did not use.\n";
    }
    return s.str();
}

void write_correction_report(const std::filesystem::path& folder, const CorrectionRecord& r) {
    const std::string summary = correction_summary(r);
    write_report_folder(folder, [&](const std::filesystem::path& temp) {
        write_file_synced(temp / "summary.md", summary);
        if (r.before && r.after) {
            for (const auto& [name, record] :
                 {std::pair{"before", &*r.before}, std::pair{"after", &*r.after}}) {
                std::filesystem::create_directory(temp / name);
                write_file_synced(temp / name / "verification.json", verification_json(*record));
                write_file_synced(temp / name / "summary.md", verification_summary(*record));
            }
        }
    });
}

} // namespace fpp::calib
