// Which pose a session should take next (see session_advice.hpp).

#include "session_advice.hpp"

#include "fpp/calib/stereo_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

namespace fpp::calib {

std::string PoseSuggestion::words() const {
    std::ostringstream o;
    if (tilt_deg < 5)
        o << "hold the board facing the camera";
    else
        o << "tilt the board about " << std::lround(tilt_deg) << " degrees (its " << far_edge
          << " edge away from the camera)";
    o << ", in the " << image_region << " of the image, at about "
      << std::lround(depth_mm / 10) * 10 << " mm";
    return o.str();
}

namespace detail {

namespace {

constexpr double kDeg = std::numbers::pi / 180;

Mat3 axis_rotation(const Vec3& axis, double angle) {
    const double c = std::cos(angle), s = std::sin(angle), C = 1 - c;
    const double x = axis[0], y = axis[1], z = axis[2];
    return {c + x * x * C,     x * y * C - z * s, x * z * C + y * s,
            y * x * C + z * s, c + y * y * C,     y * z * C - x * s,
            z * x * C - y * s, z * y * C + x * s, c + z * z * C};
}

Vec3 rotate_and_shift(const Mat3& R, const Vec3& v, const Vec3& t = {0, 0, 0}) {
    return {R[0] * v[0] + R[1] * v[1] + R[2] * v[2] + t[0],
            R[3] * v[0] + R[4] * v[1] + R[5] * v[2] + t[1],
            R[6] * v[0] + R[7] * v[1] + R[8] * v[2] + t[2]};
}

const char* region_name(int column, int row) {
    static const char* names[3][3] = {{"upper left", "top middle", "upper right"},
                                      {"left middle", "centre", "right middle"},
                                      {"lower left", "bottom middle", "lower right"}};
    return names[row][column];
}

// Whether every corner shows in both images (margin: 3 % of each side) and
// the board faces both devices within 70 degrees.
bool visible(const StereoCalibration& c, const std::vector<Vec3>& corners, const Vec3& normal,
             const Vec3& centre) {
    const auto inside = [](const Vec2& p, Size size) {
        const double mu = 0.03 * size.width, mv = 0.03 * size.height;
        return p[0] >= mu && p[0] <= size.width - 1 - mu && p[1] >= mv &&
               p[1] <= size.height - 1 - mv;
    };
    for (const Vec3& x : corners) {
        if (!(x[2] > 0) || !inside(c.camera_pixel(x), c.camera_size) ||
            !inside(c.projector_pixel(x), c.projector_size))
            return false;
    }
    const auto facing = [&](const Vec3& eye) {
        const Vec3 v{eye[0] - centre[0], eye[1] - centre[1], eye[2] - centre[2]};
        const double cosine = std::fabs(normal[0] * v[0] + normal[1] * v[1] + normal[2] * v[2]) /
                              std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        return cosine > std::cos(70 * kDeg);
    };
    return facing({0, 0, 0}) && facing(c.projector_centre());
}

} // namespace

SessionDepths board_centre_depths(const RigState& s, const std::vector<Vec3>& board,
                                  const std::vector<bool>& pose_used) {
    Vec3 centre{0, 0, 0};
    for (const Vec3& p : board)
        for (int k = 0; k < 3; ++k)
            centre[std::size_t(k)] += p[std::size_t(k)] / double(board.size());
    std::vector<double> z;
    for (std::size_t i = 0; i < s.poses.size(); ++i)
        if (pose_used[i])
            z.push_back(rotate_and_shift(s.poses[i].R, centre, s.poses[i].t)[2]);
    SessionDepths d;
    if (z.empty())
        return d;
    std::sort(z.begin(), z.end());
    d.near_mm = z.front();
    d.middle_mm = z[z.size() / 2];
    d.far_mm = z.back();
    return d;
}

Advice suggest_poses(const AdviceInputs& in) {
    const RigState& s = *in.state;
    const CalibrationCovariance& cov = *in.covariance;
    const Eigen::VectorXd& g = *in.gradient;
    const Eigen::VectorXd h = cov.transfer.transpose() * g;
    const double own = g.dot(cov.own * g);
    const Eigen::Index n = cov.pose_stage_normal.rows();
    const auto sigma_with = [&](const Eigen::MatrixXd* added) {
        Eigen::MatrixXd A = cov.pose_stage_normal;
        if (added)
            A.topLeftCorner(added->rows(), added->cols()) += *added;
        // Scaled to unit diagonal before the factorisation (focal lengths
        // and distortion terms side by side).
        Eigen::VectorXd d = A.diagonal().cwiseSqrt();
        for (Eigen::Index k = 0; k < n; ++k)
            if (!(d(k) > 0))
                d(k) = 1;
        const Eigen::MatrixXd scaled = d.asDiagonal().inverse() * A * d.asDiagonal().inverse();
        const Eigen::VectorXd hs = d.asDiagonal().inverse() * h;
        const double v = cov.pose_stage_variance * hs.dot(scaled.ldlt().solve(hs)) + own;
        return std::sqrt(std::max(v, 0.0));
    };
    Advice out;
    out.sigma_mm = sigma_with(nullptr);

    const StereoCalibration model = calibration_of(s, in.camera_size, in.projector_size);
    Vec3 centre_b{0, 0, 0};
    for (const Vec3& p : in.board)
        for (int k = 0; k < 3; ++k)
            centre_b[std::size_t(k)] += p[std::size_t(k)] / double(in.board.size());

    // The corners' information for the pose-holding adjustment: no
    // regularisation (A has it already), the candidate's own pose last.
    const GridRegularisation none{0, 0, 0};
    std::vector<PoseSuggestion> candidates;
    const double depths[3] = {in.depths.near_mm, in.depths.middle_mm, in.depths.far_mm};
    const double tilts[4] = {0, 20, 35, 45};
    // Turns about the board's own axes: +X tips its bottom edge away (camera
    // y points down), and so on round the four edges.
    struct Turn {
        Vec3 axis;
        double sign;
        const char* far_edge;
    };
    const Turn turns[4] = {{{1, 0, 0}, 1, "bottom"},
                           {{1, 0, 0}, -1, "top"},
                           {{0, 1, 0}, 1, "left"},
                           {{0, 1, 0}, -1, "right"}};
    std::vector<Vec3> corners(in.board.size());
    for (int row = 0; row < 3; ++row)
        for (int column = 0; column < 3; ++column) {
            const Vec2 pixel{(0.2 + 0.3 * column) * (in.camera_size.width - 1),
                             (0.2 + 0.3 * row) * (in.camera_size.height - 1)};
            Vec2 ray{};
            if (!model.camera_ray(pixel, ray))
                continue;
            for (double depth : depths)
                for (double tilt : tilts)
                    for (int k = 0; k < (tilt == 0 ? 1 : 4); ++k) {
                        const Turn& turn = turns[k];
                        const Mat3 R = axis_rotation(turn.axis, turn.sign * tilt * kDeg);
                        const Vec3 centre{ray[0] * depth, ray[1] * depth, depth};
                        const Vec3 rc = rotate_and_shift(R, centre_b);
                        const Vec3 t{centre[0] - rc[0], centre[1] - rc[1], centre[2] - rc[2]};
                        for (std::size_t i = 0; i < in.board.size(); ++i)
                            corners[i] = rotate_and_shift(R, in.board[i], t);
                        if (!visible(model, corners, {R[2], R[5], R[8]}, centre))
                            continue;
                        PoseSuggestion p;
                        p.R = R;
                        p.t = t;
                        p.image_point = pixel;
                        p.depth_mm = depth;
                        p.tilt_deg = tilt;
                        p.far_edge = tilt == 0 ? "" : turn.far_edge;
                        p.image_region = region_name(column, row);
                        candidates.push_back(p);
                    }
        }

    for (PoseSuggestion& p : candidates) {
        RigState one = s;
        one.poses = {RigidPose{p.R, p.t}};
        std::vector<CornerObservation> observed;
        for (const Vec3& b : in.board) {
            const Vec3 x = rotate_and_shift(p.R, b, p.t);
            observed.push_back({0, b, model.camera_pixel(x), model.projector_pixel(x)});
        }
        const NormalEquations e =
            normal_equations(one, observed, {}, {true}, cov.pose_stage, none, nullptr);
        // Its columns: the stage's own (as A's first ones), then its pose.
        const Eigen::Index shared = e.A.rows() - 6;
        const Eigen::MatrixXd app = e.A.bottomRightCorner(6, 6);
        const Eigen::MatrixXd anp = e.A.topRightCorner(shared, 6);
        const Eigen::MatrixXd added =
            e.A.topLeftCorner(shared, shared) - anp * app.ldlt().solve(anp.transpose());
        p.sigma_mm = sigma_with(&added);
    }
    std::sort(
        candidates.begin(), candidates.end(),
        [](const PoseSuggestion& a, const PoseSuggestion& b) { return a.sigma_mm < b.sigma_mm; });
    if (int(candidates.size()) > in.count)
        candidates.resize(std::size_t(std::max(in.count, 0)));
    out.next = std::move(candidates);
    return out;
}

} // namespace detail
} // namespace fpp::calib
