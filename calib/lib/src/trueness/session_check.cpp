// Whether a calibration session is enough (see session_check.hpp).

#include "fpp/calib/session_check.hpp"

#include "fpp/enum_names.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace fpp::calib {

void SessionCheckOptions::validate() const {
    const auto bad = [](const std::string& field, const std::string& why) {
        throw std::invalid_argument("session check option " + field + ": " + why);
    };
    if (!(target_mm > 0) || !std::isfinite(target_mm))
        bad("target_mm", "must be a positive length");
    if (suggestions < 0 || suggestions > 100)
        bad("suggestions", "must be 0 to 100");
    if (!(too_weak_factor > 1) || !std::isfinite(too_weak_factor))
        bad("too_weak_factor", "must be above 1");
    if (coverage_cells_across < 1 || coverage_cells_across > 256)
        bad("coverage_cells_across", "must be 1 to 256");
}

constexpr EnumName<SessionVerdict> kSessionVerdictNames[] = {
    {SessionVerdict::enough, "enough"},
    {SessionVerdict::not_yet, "not yet"},
    {SessionVerdict::too_weak, "too weak"},
};

const char* to_string(SessionVerdict verdict) {
    return name_of(kSessionVerdictNames, verdict);
}

namespace {

std::string um(double mm) {
    std::ostringstream o;
    o << std::lround(mm * 1000) << " um";
    return o.str();
}

} // namespace

SessionCheck too_weak_session(const std::string& why, const SessionCheckOptions& options) {
    SessionCheck c;
    c.verdict = SessionVerdict::too_weak;
    c.reason = why;
    c.target_mm = options.target_mm;
    return c;
}

SessionCheck check_session(const SessionResult& session, const SessionCheckOptions& options) {
    options.validate();
    SessionCheck c;
    c.target_mm = options.target_mm;
    c.poses_found = static_cast<int>(session.poses.size());
    c.poses_used = static_cast<int>(session.calibrated.size());
    c.trueness = session.stereo.calibration.trueness;
    c.next = session.stereo.next_poses;
    if (int(c.next.size()) > options.suggestions)
        c.next.resize(std::size_t(options.suggestions));

    // Coverage of the camera image by the corners of the poses used.
    const Size image = session.camera_size;
    const int cell =
        std::max(1, std::max(image.width, image.height) / options.coverage_cells_across);
    const int cx = (image.width + cell - 1) / cell, cy = (image.height + cell - 1) / cell;
    c.coverage = Image<float>(Size{cx, cy}, 1, 0.0f);
    c.coverage_cell_px = cell;
    for (const PoseObservations& o : session.observations)
        for (const Vec2& p : o.camera) {
            const int x = std::clamp(int(std::floor((p[0] + 0.5) / cell)), 0, cx - 1);
            const int y = std::clamp(int(std::floor((p[1] + 0.5) / cell)), 0, cy - 1);
            c.coverage.at(x, y, 0) += 1;
        }
    int covered = 0;
    for (std::size_t k = 0; k < c.coverage.pixel_count(); ++k)
        covered += c.coverage.data()[k] > 0;
    c.coverage_fraction = double(covered) / double(c.coverage.pixel_count());

    // Tilts: the board's normal (its pose's z axis) against the optical axis.
    c.min_tilt_deg = 180;
    c.max_tilt_deg = 0;
    for (std::size_t i = 0; i < session.stereo.board_poses.size(); ++i) {
        const Mat3& R = session.stereo.board_poses[i].R;
        const double tilt = std::acos(std::min(1.0, std::fabs(R[8]))) * 180 / std::numbers::pi;
        c.min_tilt_deg = std::min(c.min_tilt_deg, tilt);
        c.max_tilt_deg = std::max(c.max_tilt_deg, tilt);
    }

    const double sigma = c.trueness.known() ? c.trueness.middle().along_depth_mm : 0;
    if (!c.trueness.known()) {
        c.verdict = SessionVerdict::too_weak;
        c.reason = "its calibration leaves a parameter undetermined (the boards' poses do not "
                   "tell the depth scale apart from the lens); add poses tilted 30 degrees or "
                   "more at different places in the image";
    } else if (sigma <= options.target_mm) {
        c.verdict = SessionVerdict::enough;
        c.reason = "the depth scale's sigma, " + um(sigma) + " per " +
                   std::to_string(std::lround(c.trueness.length_mm)) +
                   " mm, is within the target " + um(options.target_mm);
    } else if (sigma > options.too_weak_factor * options.target_mm) {
        c.verdict = SessionVerdict::too_weak;
        std::ostringstream why;
        why << "the depth scale's sigma, " << um(sigma) << ", is over " << options.too_weak_factor
            << " times the target";
        if (c.max_tilt_deg < 15)
            why << ": every board faces the camera (tilts up to " << std::lround(c.max_tilt_deg)
                << " degrees), which does not tell the depth "
                   "scale from the focal length; tilt the board 30 degrees or more";
        else if (c.coverage_fraction < 0.5)
            why << ": the corners cover " << std::lround(100 * c.coverage_fraction)
                << " % of the image; place boards near its edges and corners";
        c.reason = why.str();
    } else {
        c.verdict = SessionVerdict::not_yet;
        c.reason = "the depth scale's sigma, " + um(sigma) + " per " +
                   std::to_string(std::lround(c.trueness.length_mm)) + " mm, is above the target " +
                   um(options.target_mm);
    }
    return c;
}

std::string SessionCheck::text() const {
    std::ostringstream o;
    o << "Session: " << to_string(verdict) << ": " << reason << ".\n";
    if (poses_found > 0)
        o << "Poses: " << poses_used << " used of " << poses_found << " found; tilts "
          << std::lround(min_tilt_deg) << " to " << std::lround(max_tilt_deg)
          << " degrees; corners over " << std::lround(100 * coverage_fraction)
          << " % of the image (" << coverage.width() << " x " << coverage.height() << " cells).\n";
    if (trueness.known())
        o << trueness_summary(trueness);
    if (verdict != SessionVerdict::enough && !next.empty()) {
        o << "Next pose: " << next.front().words() << " (the depth scale's sigma then about "
          << um(next.front().sigma_mm) << ").\n";
        for (std::size_t k = 1; k < next.size(); ++k)
            o << "  or: " << next[k].words() << " (" << um(next[k].sigma_mm) << ").\n";
    }
    return o.str();
}

} // namespace fpp::calib
