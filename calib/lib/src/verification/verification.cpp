// VDI/VDE 2634-2 figures of a certified artefact, the certificate's
// consistency with the scans, and the verdicts (see the header).

#include "fpp/calib/verification.hpp"

#include "fpp/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace fpp::calib {

namespace {

std::string mm(double v, int digits = 3) {
    char text[48];
    std::snprintf(text, sizeof text, "%.*f", digits, v);
    return text;
}

std::string signed_mm(double v, int digits = 3) {
    char text[48];
    std::snprintf(text, sizeof text, "%+.*f", digits, v);
    return text;
}

double distance(const Vec3& a, const Vec3& b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                     (a[2] - b[2]) * (a[2] - b[2]));
}

double length(const Vec3& a) {
    return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

std::string point_text(const Vec3& p) {
    char text[96];
    std::snprintf(text, sizeof text, "(%.1f, %.1f, %.1f) mm", p[0], p[1], p[2]);
    return text;
}

std::string sphere_field(std::size_t index) {
    return "sphere " + std::to_string(index + 1);
}

// Diameters close enough to be found by one search (within its tolerance).
bool same_search(double a, double b) {
    return std::abs(a - b) <= std::max(1.0, 0.1 * std::min(a, b));
}

struct Candidate {
    FoundSphere found;
    double searched_diameter = 0;
};

// Every sphere of the artefact's diameters in view, each once.
std::vector<Candidate> sphere_candidates(const Artefact& artefact, const Image<float>& xyz,
                                         std::span<const std::uint8_t> usable,
                                         const ArtefactSearchOptions& options) {
    std::vector<double> searched;
    for (const double d : artefact.sphere_diameters_mm)
        if (std::none_of(searched.begin(), searched.end(),
                         [&](double s) { return same_search(s, d); }))
            searched.push_back(d);
    std::vector<Candidate> all;
    for (const double d : searched)
        for (FoundSphere& f : find_spheres(xyz, usable, d, options)) {
            const double fitted = f.figures.diameter;
            auto same = std::find_if(all.begin(), all.end(), [&](const Candidate& c) {
                return distance(c.found.figures.fit.centre, f.figures.fit.centre) <
                       0.5 * std::min(d, c.searched_diameter);
            });
            if (same == all.end())
                all.push_back(Candidate{std::move(f), d});
            else if (std::abs(fitted - d) <
                     std::abs(same->found.figures.diameter - same->searched_diameter))
                *same = Candidate{std::move(f), d};
        }
    return all;
}

// The artefact's sphere each of `chosen` is: by diameter when the
// certificate tells them apart, else from left to right in the image
// (smaller X first).
std::vector<std::size_t> assign_spheres(const Artefact& artefact,
                                        const std::vector<Candidate>& chosen) {
    const std::size_t n = artefact.sphere_count();
    std::vector<std::size_t> order(chosen.size());
    for (std::size_t k = 0; k < order.size(); ++k)
        order[k] = k;
    const bool told_apart_by_size =
        n == 2 && !same_search(artefact.sphere_diameters_mm[0], artefact.sphere_diameters_mm[1]);
    if (told_apart_by_size) {
        // Candidate k belongs to the certified diameter it was found with.
        for (std::size_t k = 0; k < chosen.size(); ++k)
            order[k] = chosen[k].searched_diameter == artefact.sphere_diameters_mm[0] ? 0 : 1;
        if (chosen.size() == 2 && order[0] == order[1])
            order[1] = 1 - order[0];
        return order;
    }
    std::vector<std::size_t> by_x = order;
    std::sort(by_x.begin(), by_x.end(), [&](std::size_t a, std::size_t b) {
        return chosen[a].found.figures.fit.centre[0] < chosen[b].found.figures.fit.centre[0];
    });
    for (std::size_t rank = 0; rank < by_x.size(); ++rank)
        order[by_x[rank]] = rank;
    return order;
}

MeasuredSphere measured_sphere(const Artefact& artefact, std::size_t index, const FoundSphere& f,
                               const Image<float>& truth_xyz) {
    MeasuredSphere s;
    s.index = index;
    s.certified_diameter = artefact.sphere_diameters_mm[index];
    s.centre = f.figures.fit.centre;
    s.diameter = f.figures.diameter;
    s.form = f.figures.form_trimmed.range;
    s.form_all_points = f.figures.form;
    s.size_error = s.diameter - s.certified_diameter;
    s.rms = f.figures.fit.fit.rms;
    s.coverage = f.coverage;
    s.points_used = f.points.size();
    s.pixels = f.pixels;
    s.residuals = f.figures.fit.fit.residuals;
    if (!truth_xyz.empty() && truth_xyz.size().area() > 0 && truth_xyz.channels() == 3) {
        std::vector<Vec3> truth;
        for (const std::uint32_t i : f.pixels) {
            const float* p = truth_xyz.data() + 3 * std::size_t(i);
            if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
                truth.push_back({double(p[0]), double(p[1]), double(p[2])});
        }
        try {
            s.truth_centre = fit_sphere(truth).centre;
        } catch (const FitError&) {
            // No truth figure for this sphere.
        }
    }
    return s;
}

void measure_plane(const Artefact& artefact, const Image<float>& xyz,
                   std::span<const std::uint8_t> usable, const std::filesystem::path& capture,
                   const VerificationOptions& options, MeasuredPosition& m) {
    FoundPlane found;
    try {
        found = find_plane(xyz, usable, artefact.plane_width_mm, artefact.plane_height_mm,
                           options.search);
    } catch (const FitError& e) {
        throw InputError(capture, "plane", e.what());
    }
    MeasuredPlane p;
    p.flatness = found.figures.trimmed.range;
    p.flatness_all_points = found.figures.flatness;
    p.rms = found.figures.fit.fit.rms;
    p.extent_mm[0] = found.extent_mm[0];
    p.extent_mm[1] = found.extent_mm[1];
    p.points_used = found.points.size();
    p.pixels = found.pixels;
    p.residuals = found.figures.fit.fit.residuals;
    m.plane = std::move(p);
}

// Refuses two spheres whose discs overlap in the image: one hides part of
// the other, and the points along that edge belong to both.
void check_apart_in_view(const MeasuredPosition& m, const std::filesystem::path& capture) {
    if (m.spheres.size() != 2)
        return;
    const MeasuredSphere &a = m.spheres[0], &b = m.spheres[1];
    const double la = length(a.centre), lb = length(b.centre);
    const double cos_apart =
        (a.centre[0] * b.centre[0] + a.centre[1] * b.centre[1] + a.centre[2] * b.centre[2]) /
        (la * lb);
    const double apart = std::acos(std::clamp(cos_apart, -1.0, 1.0));
    const double touching = std::asin(std::min(1.0, a.diameter / 2 / la)) +
                            std::asin(std::min(1.0, b.diameter / 2 / lb));
    if (apart <= touching)
        throw InputError(capture, "spheres",
                         "the two spheres are too close to tell apart in the camera's view: "
                         "one hides part of the other (" +
                             mm(apart * 180 / 3.14159265358979323846, 1) +
                             " degrees apart, their discs span " +
                             mm(touching * 180 / 3.14159265358979323846, 1) +
                             "): turn the bar across the line of sight");
}

} // namespace

MeasuredPosition measure_position(const Artefact& artefact, const Image<float>& xyz,
                                  const std::filesystem::path& capture,
                                  const VerificationOptions& options,
                                  const Image<float>& truth_xyz) {
    MeasuredPosition m;
    m.capture = capture;
    m.camera = xyz.size();
    const std::vector<std::uint8_t> usable = usable_points(xyz, options.search);
    if (artefact.kind == ArtefactKind::plane) {
        measure_plane(artefact, xyz, usable, capture, options, m);
        return m;
    }
    std::vector<Candidate> all = sphere_candidates(artefact, xyz, usable, options.search);
    const std::size_t n = artefact.sphere_count();
    std::string diameters;
    for (const double d : artefact.sphere_diameters_mm)
        diameters += (diameters.empty() ? "" : " and ") + mm(d);
    // Whole spheres first, then by points.
    std::stable_sort(all.begin(), all.end(), [&](const Candidate& a, const Candidate& b) {
        const bool wa = a.found.coverage >= options.min_coverage,
                   wb = b.found.coverage >= options.min_coverage;
        return wa != wb ? wa : a.found.points.size() > b.found.points.size();
    });
    const std::size_t whole =
        std::size_t(std::count_if(all.begin(), all.end(), [&](const Candidate& c) {
            return c.found.coverage >= options.min_coverage;
        }));
    if (whole > n) {
        std::string list;
        for (const Candidate& c : all)
            list += "\n  diameter " + mm(c.found.figures.diameter) + " mm at " +
                    point_text(c.found.figures.fit.centre);
        throw InputError(
            capture, "spheres",
            std::to_string(whole) + " spheres of the certified diameter (" + diameters +
                " mm) in view, the " + to_string(artefact.kind) + " has " + std::to_string(n) +
                ": which belong to it is ambiguous; take the others out of view:" + list);
    }
    if (all.size() < n)
        throw InputError(capture, "spheres",
                         "found " + std::to_string(all.size()) + " of the " + std::to_string(n) +
                             " spheres of the certified diameter (" + diameters +
                             " mm): a sphere missing (out of the view, unlit, or another "
                             "artefact?)");
    all.resize(n);
    const std::vector<std::size_t> index = assign_spheres(artefact, all);
    m.spheres.resize(n);
    for (std::size_t k = 0; k < n; ++k)
        m.spheres[index[k]] = measured_sphere(artefact, index[k], all[k].found, truth_xyz);
    check_apart_in_view(m, capture);
    for (const MeasuredSphere& s : m.spheres)
        if (s.coverage < options.min_coverage)
            throw InputError(capture, sphere_field(s.index),
                             "too little of the sphere's surface to fit (" +
                                 std::to_string(s.points_used) + " points at " +
                                 point_text(s.centre) + " cover " + mm(s.coverage, 2) +
                                 " of the hemisphere facing the camera, the minimum is " +
                                 mm(options.min_coverage, 2) +
                                 "): cut by the edge of the view or of the projector's light, "
                                 "or hidden");
    if (artefact.kind == ArtefactKind::ball_bar) {
        m.length = distance(m.spheres[0].centre, m.spheres[1].centre);
        m.spacing_error = *m.length - artefact.centre_distance_mm;
        if (m.spheres[0].truth_centre && m.spheres[1].truth_centre)
            m.truth_spacing_error =
                distance(*m.spheres[0].truth_centre, *m.spheres[1].truth_centre) -
                artefact.centre_distance_mm;
    }
    return m;
}

void check_certificate(const Artefact& artefact, const std::vector<MeasuredPosition>& positions,
                       const VerificationOptions& options) {
    const double limit = options.max_credible_error_mm;
    const std::string beyond = " mm, far more than a scanner could be off (the limit is " +
                               mm(limit) +
                               " mm, --max-credible-error): the certificate or the artefact "
                               "file does not belong to this artefact; nothing was judged";
    double largest_size_error = 0;
    for (const MeasuredPosition& p : positions)
        for (const MeasuredSphere& s : p.spheres) {
            largest_size_error = std::max(largest_size_error, std::abs(s.size_error));
            if (std::abs(s.size_error) > limit)
                throw InputError(
                    artefact.origin, "sphere_diameters_mm[" + std::to_string(s.index) + "]",
                    "certified " + mm(s.certified_diameter) + " mm, but " + p.capture.string() +
                        " measures " + mm(s.diameter) + " mm: " + signed_mm(s.size_error) + beyond);
        }
    for (std::size_t k = 0; k < positions.size(); ++k) {
        const MeasuredPosition& p = positions[k];
        if (!p.spacing_error || std::abs(*p.spacing_error) <= limit)
            continue;
        // A scanner whose scale were off by SD / L would show the diameters
        // off by the same share: say what they show.
        const double d = artefact.sphere_diameters_mm[0];
        throw InputError(artefact.origin, "centre_distance_mm",
                         "certified " + mm(artefact.centre_distance_mm) + " mm, but position " +
                             std::to_string(k + 1) + " (" + p.capture.string() + ") measures " +
                             mm(*p.length) + " mm: " + signed_mm(*p.spacing_error) + beyond +
                             " (a scale error that large would put the " + mm(d, 0) +
                             " mm spheres " +
                             mm(std::abs(*p.spacing_error) * d / artefact.centre_distance_mm) +
                             " mm off; they are off by at most " + mm(largest_size_error) + " mm)");
    }
}

std::vector<FigureVerdict> verdicts(const Artefact& artefact,
                                    const std::vector<MeasuredPosition>& positions,
                                    const MaximumPermissibleErrors& mpe) {
    auto verdict = [](std::string name, std::vector<double> values, std::optional<double> limit) {
        FigureVerdict v{std::move(name), std::move(values), 0, limit};
        for (const double x : v.values)
            v.worst = std::max(v.worst, std::abs(x));
        return v;
    };
    std::vector<FigureVerdict> out;
    if (artefact.kind == ArtefactKind::plane) {
        std::vector<double> flatness;
        for (const MeasuredPosition& p : positions)
            if (p.plane)
                flatness.push_back(p.plane->flatness);
        out.push_back(verdict("F", flatness, mpe.flatness_mm));
        return out;
    }
    std::vector<double> spacing, form, size;
    for (const MeasuredPosition& p : positions) {
        if (p.spacing_error)
            spacing.push_back(*p.spacing_error);
        for (const MeasuredSphere& s : p.spheres) {
            form.push_back(s.form);
            size.push_back(s.size_error);
        }
    }
    if (artefact.kind == ArtefactKind::ball_bar)
        out.push_back(verdict("SD", spacing, mpe.spacing_mm));
    out.push_back(verdict("P_F", form, mpe.form_mm));
    out.push_back(verdict("P_S", size, mpe.size_mm));
    return out;
}

} // namespace fpp::calib
