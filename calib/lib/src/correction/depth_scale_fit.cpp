#include "fpp/calib/depth_scale.hpp"

#include "fpp/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace fpp::calib {

namespace {

double norm(const Vec3& v) {
    return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

// |(d_x, d_y, k d_z)|, mm.
double scaled_length(const Vec3& d, double k) {
    return norm(Vec3{d[0], d[1], k * d[2]});
}

std::string fixed(double value, int digits) {
    char text[64];
    std::snprintf(text, sizeof text, "%.*f", digits, value);
    return text;
}

std::string signed_fixed(double value, int digits) {
    char text[64];
    std::snprintf(text, sizeof text, "%+.*f", digits, value);
    return text;
}

} // namespace

DepthScaleFit fit_depth_scale(const std::vector<LengthObservation>& positions, double certified_mm,
                              double certificate_sigma_mm, const DepthScaleOptions& options) {
    if (positions.size() < 2)
        throw InputError("command line", "CAPTURE",
                         std::to_string(positions.size()) +
                             " position used: a depth scale needs at least 2 positions of the "
                             "artefact (their lengths must agree with each other to be trusted)");
    DepthScaleFit fit;
    for (const LengthObservation& p : positions) {
        const double length = norm(p.vector);
        fit.depth_share.push_back(length > 0 ? std::abs(p.vector[2]) / length : 0);
        fit.before_mm.push_back(length - certified_mm);
        if (fit.depth_share.back() >= options.min_depth_share)
            ++fit.depth_positions;
    }
    if (fit.depth_positions < options.min_depth_positions) {
        std::ostringstream why;
        why << fit.depth_positions << " of the " << positions.size()
            << " used positions reach in depth (|d_z| / |d| at least "
            << fixed(options.min_depth_share, 2) << "; need " << options.min_depth_positions
            << "): a depth scale cannot be seen from lengths across the image. Depth shares:";
        for (std::size_t i = 0; i < positions.size(); ++i)
            why << " " << positions[i].capture.string() << " " << fixed(fit.depth_share[i], 2)
                << (i + 1 < positions.size() ? "," : "");
        why << ". Tilt the bar in depth (e.g. the VDI positions with one end 75 mm nearer)";
        throw InputError("command line", "CAPTURE", why.str());
    }

    // Gauss-Newton on k: r_i = |(d_x, d_y, k d_z)| - L, dr_i/dk = k d_z^2 / |.|.
    double k = 1, jj = 0, j_sum = 0;
    for (int iteration = 0; iteration < 8; ++iteration) {
        double jr = 0;
        jj = 0;
        j_sum = 0;
        for (const LengthObservation& p : positions) {
            const double length = scaled_length(p.vector, k);
            const double j = k * p.vector[2] * p.vector[2] / length;
            jr += j * (length - certified_mm);
            jj += j * j;
            j_sum += j;
        }
        const double step = -jr / jj;
        k += step;
        if (std::abs(step) < 1e-12)
            break;
    }
    fit.scale = k;
    double rr = 0;
    for (const LengthObservation& p : positions) {
        fit.residual_mm.push_back(scaled_length(p.vector, k) - certified_mm);
        rr += fit.residual_mm.back() * fit.residual_mm.back();
    }
    fit.scatter_mm = std::sqrt(rr / double(positions.size() - 1));
    // The scatter averages over the positions; the certificate's error is
    // the same in all of them and moves k by u sum(J) / sum(J^2).
    const double from_scatter = fit.scatter_mm * fit.scatter_mm / jj;
    const double from_certificate = certificate_sigma_mm * j_sum / jj;
    fit.sigma = std::sqrt(from_scatter + from_certificate * from_certificate);
    return fit;
}

double depth_scale_limit(const Trueness& predicted, double certified_mm,
                         double certificate_sigma_mm, const DepthScaleOptions& options) {
    const double trueness_share = predicted.known()
                                      ? predicted.middle().along_depth_mm / predicted.length_mm
                                      : options.unknown_trueness_ppm * 1e-6;
    return options.max_sigmas * (trueness_share + certificate_sigma_mm / certified_mm);
}

void check_depth_scale_fit(const DepthScaleFit& fit,
                           const std::vector<LengthObservation>& positions,
                           const Trueness& predicted, double certified_mm,
                           double certificate_sigma_mm, const std::filesystem::path& artefact,
                           const std::filesystem::path& calibration,
                           const DepthScaleOptions& options) {
    std::ostringstream lengths;
    for (std::size_t i = 0; i < positions.size(); ++i)
        lengths << "\n  " << positions[i].capture.string() << ": SD "
                << signed_fixed(fit.before_mm[i], 4) << " mm, after the fit "
                << signed_fixed(fit.residual_mm[i], 4) << " mm (depth share "
                << fixed(fit.depth_share[i], 2) << ")";
    for (std::size_t i = 0; i < positions.size(); ++i)
        if (std::abs(fit.residual_mm[i]) > options.max_position_residual_mm)
            throw InputError(
                artefact, "centre_distance_mm",
                "refused as inconsistent, never corrected: the position " +
                    positions[i].capture.string() + " disagrees with the others by " +
                    signed_fixed(fit.residual_mm[i], 4) + " mm after the best depth scale (" +
                    depth_scale_text(fit) + "; at most " +
                    fixed(options.max_position_residual_mm, 3) +
                    " mm): the certificate or a capture is wrong, not the depth scale." +
                    lengths.str());
    const double limit = depth_scale_limit(predicted, certified_mm, certificate_sigma_mm, options);
    if (std::abs(fit.scale - 1) > limit)
        throw InputError(
            artefact, "centre_distance_mm",
            "refused as inconsistent, never corrected: the lengths ask for a depth scale of " +
                signed_fixed(fit.correction_ppm(), 0) + " ppm, beyond the " +
                fixed(limit * 1e6, 0) + " ppm that " + fixed(options.max_sigmas, 0) + " sigma of " +
                calibration.string() + "'s predicted trueness (" +
                (predicted.known() ? fixed(predicted.depth_ppm(), 0) + " ppm along depth"
                                   : std::string("unknown, taken as ") +
                                         fixed(options.unknown_trueness_ppm, 0) + " ppm") +
                ") and the certificate's uncertainty allow: the certificate (or its file), the "
                "calibration or the captures are not what they should be." +
                lengths.str());
}

Trueness trueness_from_fit(const Trueness& predicted, const DepthScaleFit& fit,
                           double certified_mm) {
    Trueness t = predicted;
    if (!t.known()) {
        t.length_mm = certified_mm;
        for (LengthSigma& s : t.at)
            s.across_mm = 0;
    }
    for (LengthSigma& s : t.at)
        s.along_depth_mm = fit.sigma * t.length_mm;
    return t;
}

std::string depth_scale_text(const DepthScaleFit& fit) {
    return "k - 1 = " + signed_fixed(fit.correction_ppm(), 0) + " ppm +- " +
           fixed(fit.sigma * 1e6, 0) + " ppm (" + std::to_string(fit.residual_mm.size()) +
           " positions, " + std::to_string(fit.depth_positions) + " reaching in depth, scatter " +
           fixed(fit.scatter_mm, 4) + " mm)";
}

} // namespace fpp::calib
