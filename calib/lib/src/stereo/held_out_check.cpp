// Leave-one-pose-out check of a stereo calibration (see fpp/calib/held_out_check.hpp).

#include "fpp/calib/held_out_check.hpp"

#include "fpp/calib/sv_reconstruct.hpp"

#include <Eigen/Dense>

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace fpp::calib {

namespace {

// Best similarity (with_scale) or rigid transform from `model` to `measured`
// (Umeyama); returns the RMS residual and the scale.
double fit_transform(const std::vector<Vec3>& model, const std::vector<Vec3>& measured,
                     bool with_scale, double& scale) {
    const auto n = static_cast<Eigen::Index>(model.size());
    Eigen::Matrix3Xd a(3, n), b(3, n);
    for (Eigen::Index k = 0; k < n; ++k) {
        a.col(k) << model[std::size_t(k)][0], model[std::size_t(k)][1], model[std::size_t(k)][2];
        b.col(k) << measured[std::size_t(k)][0], measured[std::size_t(k)][1],
            measured[std::size_t(k)][2];
    }
    const Eigen::Matrix4d T = Eigen::umeyama(a, b, with_scale);
    scale = T.block<3, 1>(0, 0).norm();
    const Eigen::Matrix3Xd moved = (T.block<3, 3>(0, 0) * a).colwise() + T.block<3, 1>(0, 3);
    return std::sqrt((moved - b).colwise().squaredNorm().sum() / double(n));
}

double distance(const Vec3& a, const Vec3& b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                     (a[2] - b[2]) * (a[2] - b[2]));
}

} // namespace

std::string HeldOutCheck::summary() const {
    std::ostringstream s;
    s.setf(std::ios::fixed);
    s.precision(4);
    s << "held-out poses (each calibrated without it, its corners measured by SV):\n";
    for (const HeldOutPose& p : poses)
        s << "  " << p.name << ": " << p.corners << " corners at " << std::setprecision(0)
          << p.distance_mm << std::setprecision(4) << " mm, fit RMS " << p.fit_rms_mm
          << " mm, scale error " << std::setprecision(1) << 1e6 * p.scale_error
          << " ppm, length error RMS " << std::setprecision(4) << p.length_rms_mm << " mm, max "
          << p.length_max_mm << " mm\n";
    s << "all: fit RMS " << fit_rms_mm << " mm, length error RMS " << length_rms_mm << " mm, max "
      << length_max_mm << " mm, scale error RMS " << std::setprecision(1) << 1e6 * scale_error_rms
      << " ppm\n";
    return s.str();
}

HeldOutCheck check_held_out(const SessionResult& session, const StereoSessionOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const std::vector<PoseObservations>& all = session.observations;
    if (all.size() < 4)
        throw std::invalid_argument("held-out check: at least 4 calibrated poses are needed");
    const double diagonal =
        std::hypot(double(session.board.inner_columns - 1), double(session.board.inner_rows - 1)) *
        session.board.square_size;
    HeldOutCheck check;
    double fit_sum = 0, length_sum = 0, scale_sum = 0;
    std::size_t fit_count = 0, length_count = 0;
    for (std::size_t k = 0; k < all.size(); ++k) {
        std::vector<PoseObservations> others;
        for (std::size_t j = 0; j < all.size(); ++j)
            if (j != k)
                others.push_back(all[j]);
        StereoOptions stereo = options.stereo;
        stereo.progress = nullptr;
        const StereoResult r =
            stereo_calibrate(others, session.camera_size, session.projector_size, stereo);
        const SvReconstructor sv(r.calibration);
        const PoseObservations& o = all[k];
        std::vector<Vec3> model, measured;
        for (std::size_t c = 0; c < o.board.size(); ++c) {
            Vec3 p{};
            if (std::isfinite(o.projector[c][0]) &&
                sv.triangulate_xy(o.camera[c][0], o.camera[c][1], o.projector[c][0],
                                  o.projector[c][1], p)) {
                model.push_back(o.board[c]);
                measured.push_back(p);
            }
        }
        HeldOutPose h;
        h.name = o.name;
        h.corners = static_cast<int>(measured.size());
        if (measured.size() < 4) {
            check.poses.push_back(h);
            continue;
        }
        double unused = 1, scale = 1;
        h.fit_rms_mm = fit_transform(model, measured, false, unused);
        fit_transform(model, measured, true, scale);
        h.scale_error = scale - 1;
        double sum = 0;
        std::size_t pairs = 0;
        for (std::size_t a = 0; a < model.size(); ++a)
            for (std::size_t b = a + 1; b < model.size(); ++b) {
                const double truth = distance(model[a], model[b]);
                if (truth < 0.5 * diagonal)
                    continue;
                const double e = distance(measured[a], measured[b]) - truth;
                sum += e * e;
                h.length_max_mm = std::max(h.length_max_mm, std::fabs(e));
                ++pairs;
            }
        h.length_rms_mm = pairs ? std::sqrt(sum / double(pairs)) : 0;
        Vec3 centre{0, 0, 0};
        for (const Vec3& p : measured)
            for (int i = 0; i < 3; ++i)
                centre[std::size_t(i)] += p[std::size_t(i)] / double(measured.size());
        h.distance_mm =
            std::sqrt(centre[0] * centre[0] + centre[1] * centre[1] + centre[2] * centre[2]);
        fit_sum += h.fit_rms_mm * h.fit_rms_mm * double(measured.size());
        fit_count += measured.size();
        length_sum += sum;
        length_count += pairs;
        scale_sum += h.scale_error * h.scale_error;
        check.length_max_mm = std::max(check.length_max_mm, h.length_max_mm);
        check.poses.push_back(h);
    }
    check.fit_rms_mm = fit_count ? std::sqrt(fit_sum / double(fit_count)) : 0;
    check.length_rms_mm = length_count ? std::sqrt(length_sum / double(length_count)) : 0;
    check.scale_error_rms = std::sqrt(scale_sum / double(check.poses.size()));
    check.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return check;
}

} // namespace fpp::calib
