// Simulated calibration sessions: board poses spread through the calibration
// volume, one rendered capture set per pose.

#include "fpp/simulator/session.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/vec3.hpp"
#include "fpp/yaml_fields.hpp"
#include "yaml_emit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace fpp::sim {

using namespace vec;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kGoldenFraction = 0.6180339887498949; // spreads k * g mod 1 evenly
constexpr double kSqrt2Fraction = 0.4142135623730951;

// Deterministic uniform numbers in [0, 1) from a 64-bit seed (splitmix64):
// the same poses on every platform and standard library.
class Uniform {
public:
    explicit Uniform(std::uint64_t seed) : state_(seed ^ 0x5DEECE66DULL) {}
    double next() {
        std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
        z ^= z >> 31;
        return static_cast<double>(z >> 11) * 0x1.0p-53;
    }

private:
    std::uint64_t state_;
};

double fraction(double v) {
    return v - std::floor(v);
}

bool inside(const Vec2& p, Size size, double margin) {
    return std::isfinite(p[0]) && std::isfinite(p[1]) && p[0] >= margin && p[1] >= margin &&
           p[0] <= size.width - 1 - margin && p[1] <= size.height - 1 - margin;
}

// The camera-frame point at depth z on the ray through the camera image centre.
Vec3 field_centre(const Rig& rig, double z) {
    Vec2 n{};
    const Vec2 centre{(rig.camera_size.width - 1) * 0.5, (rig.camera_size.height - 1) * 0.5};
    if (!rig.camera.pixel_to_normalised(centre, n))
        n = {0, 0};
    return {n[0] * z, n[1] * z, z};
}

// The camera-frame point at depth z midway between the camera's and the
// projector's image-centre rays: the middle of the common field when the
// projector's field is far off the camera's axis (a projector above the
// camera lights only part of the camera field near the rig).
Vec3 common_field_centre(const Rig& rig, double z) {
    Vec2 n{};
    const Vec2 centre{(rig.projector_size.width - 1) * 0.5, (rig.projector_size.height - 1) * 0.5};
    if (!rig.projector.pixel_to_normalised(centre, n))
        return field_centre(rig, z);
    const Mat3 Rt = transpose(rig.R);
    const Vec3 origin = rig.projector_centre_in_camera();
    const Vec3 direction = mul(Rt, Vec3{n[0], n[1], 1});
    if (!(std::fabs(direction[2]) > 1e-9))
        return field_centre(rig, z);
    const Vec3 on_projector_ray = add(origin, scale(direction, (z - origin[2]) / direction[2]));
    return scale(add(field_centre(rig, z), on_projector_ray), 0.5);
}

// The largest s in [0, 1] such that visible(s) holds, assuming visible(0) and
// a single transition (bisection to 1 %).
template <class F> double largest_visible(F visible) {
    if (visible(1.0))
        return 1.0;
    double lo = 0, hi = 1;
    for (int i = 0; i < 8; ++i) {
        const double mid = 0.5 * (lo + hi);
        (visible(mid) ? lo : hi) = mid;
    }
    return lo;
}

std::vector<Pose> checkerboard_poses(const Rig& rig, const SessionOptions& o) {
    Uniform uniform(o.seed);
    const double margin = checkerboard_margin_px(rig, o);
    std::vector<Pose> poses;
    const int n = o.poses;
    for (int k = 0; k < n; ++k) {
        const double u_depth = uniform.next(), u_roll = uniform.next(), u_shift = uniform.next();
        // Depths stratified over [near, far] in a scrambled order (golden-ratio
        // sequence) so that consecutive poses differ and the volume is covered.
        const double stratum = fraction(0.5 + k * kGoldenFraction);
        const double depth_slot = std::floor(stratum * n);
        const double z =
            o.near_mm + (o.far_mm - o.near_mm) * (depth_slot + 0.25 + 0.5 * u_depth) / n;
        // Tilts about the board's x and y axes in every direction (golden
        // angle), the first pose nearly frontal; roll about the normal.
        const double direction = 2 * kPi * fraction(k * (1 - kGoldenFraction) + 0.125);
        const double magnitude = k == 0
                                     ? 0.15 * o.max_tilt_deg
                                     : o.max_tilt_deg * (0.6 + 0.4 * fraction(k * kSqrt2Fraction));
        const double roll = o.max_roll_deg * (2 * u_roll - 1);
        const double shift_direction = 2 * kPi * fraction(k * kGoldenFraction + 0.3);
        // About the camera's axis first; about the middle of the common field
        // when the board does not fit there.
        const Vec3 centres[2] = {field_centre(rig, z), common_field_centre(rig, z)};
        bool placed = false;
        for (int attempt = 0; attempt < 24 && !placed; ++attempt) {
            const Vec3& centre = centres[attempt / 12];
            const double tilt = magnitude * std::pow(0.85, attempt % 12); // less tilt each time
            const Mat3 R = rotation_from_euler_deg(tilt * std::cos(direction),
                                                   tilt * std::sin(direction), roll);
            const double max_shift_mm = 0.35 * z; // beyond any field at these distances
            auto pose_at = [&](double s) {
                return Pose{add(centre, Vec3{s * max_shift_mm * std::cos(shift_direction),
                                             s * max_shift_mm * std::sin(shift_direction), 0.0}),
                            R};
            };
            auto visible = [&](double s) {
                return checkerboard_fully_visible(rig, o.board, pose_at(s), margin);
            };
            if (!visible(0))
                continue;
            // Shifted across the field, nearly as far as visibility allows (the lens distortion is
            // best measured near the borders of both images).
            const double s = largest_visible(visible) * (0.85 + 0.15 * u_shift);
            poses.push_back(pose_at(s));
            placed = true;
        }
        if (!placed)
            throw std::invalid_argument("session: the checkerboard does not fit inside the camera "
                                        "and projector images at " +
                                        std::to_string(z) + " mm; use a smaller board");
    }
    return poses;
}

std::vector<Pose> plane_poses(const Rig& rig, const SessionOptions& o) {
    Uniform uniform(o.seed);
    std::vector<Pose> poses;
    const int n = o.poses;
    for (int k = 0; k < n; ++k) {
        const double u_depth = uniform.next(), u_tilt = uniform.next();
        // Homogeneous displacements through the depth range, as in the paper,
        // with moderate tilts in every direction.
        const double z =
            n == 1 ? 0.5 * (o.near_mm + o.far_mm)
                   : o.near_mm + (o.far_mm - o.near_mm) * (k + 0.2 * (u_depth - 0.5)) / (n - 1);
        const double direction = 2 * kPi * fraction(k * (1 - kGoldenFraction));
        double magnitude = o.max_plane_tilt_deg * (0.4 + 0.6 * u_tilt);
        const Vec3 centre = field_centre(rig, std::clamp(z, o.near_mm, o.far_mm));
        bool placed = false;
        for (int attempt = 0; attempt < 12 && !placed; ++attempt, magnitude *= 0.7) {
            const Pose pose{centre, rotation_from_euler_deg(magnitude * std::cos(direction),
                                                            magnitude * std::sin(direction), 0)};
            if (plane_covers_camera(rig, o.plane_width_mm, o.plane_height_mm, pose)) {
                poses.push_back(pose);
                placed = true;
            }
        }
        if (!placed)
            throw std::invalid_argument("session: the plane does not cover the camera field at " +
                                        std::to_string(z) + " mm; use a larger plane");
    }
    return poses;
}

} // namespace

double checkerboard_margin_px(const Rig& rig, const SessionOptions& options) {
    const double scale = std::min(1.0, double(rig.camera_size.width) / 1600.0);
    return std::max(8.0, options.visibility_margin_px * scale);
}

CheckerboardSpec session_checkerboard() {
    CheckerboardSpec spec;
    spec.inner_columns = 11;
    spec.inner_rows = 8;
    spec.square_size = 15.0;
    spec.margin = 120.0;
    return spec;
}

bool checkerboard_fully_visible(const Rig& rig, const CheckerboardSpec& board, const Pose& pose,
                                double margin_px) {
    const double s = board.square_size;
    const double hx = ((board.inner_columns + 1) * 0.5 + 0.25) * s;
    const double hy = ((board.inner_rows + 1) * 0.5 + 0.25) * s;
    const Vec3 normal = column(pose.R, 2);
    const Vec3 projector_centre = rig.projector_centre_in_camera();
    // Both devices must see the board's face at less than 70 degrees of incidence.
    const double cos_limit = std::cos(70.0 * kPi / 180.0);
    const Vec3 to_camera = normalised(pose.centre);
    const Vec3 to_projector = normalised(sub(pose.centre, projector_centre));
    if (std::fabs(dot(normal, to_camera)) < cos_limit ||
        std::fabs(dot(normal, to_projector)) < cos_limit ||
        dot(normal, to_camera) * dot(normal, to_projector) <= 0)
        return false;
    // The outline, densely sampled (lens distortion bends straight edges; the
    // image of the inside stays within the image of the outline).
    constexpr int kSamples = 24;
    for (int e = 0; e < 4; ++e)
        for (int i = 0; i <= kSamples; ++i) {
            const double f = -1 + 2.0 * i / kSamples;
            const Vec3 local = e == 0   ? Vec3{f * hx, -hy, 0}
                               : e == 1 ? Vec3{f * hx, hy, 0}
                               : e == 2 ? Vec3{-hx, f * hy, 0}
                                        : Vec3{hx, f * hy, 0};
            const Vec3 pc = pose.to_camera(local);
            if (!(pc[2] > 1))
                return false;
            if (!inside(rig.camera.project(pc), rig.camera_size, margin_px))
                return false;
            const Vec3 pp = add(mul(rig.R, pc), rig.t);
            if (!(pp[2] > 1))
                return false;
            if (!inside(rig.projector.project(pp), rig.projector_size, margin_px))
                return false;
        }
    return true;
}

bool plane_covers_camera(const Rig& rig, double width_mm, double height_mm, const Pose& pose) {
    const Plane plane(pose, width_mm, height_mm, 1.0);
    const int w = rig.camera_size.width, h = rig.camera_size.height;
    constexpr int kSamples = 24;
    for (int e = 0; e < 4; ++e)
        for (int i = 0; i <= kSamples; ++i) {
            const double f = static_cast<double>(i) / kSamples;
            const Vec2 px = e == 0   ? Vec2{f * (w - 1), 0}
                            : e == 1 ? Vec2{f * (w - 1), h - 1.0}
                            : e == 2 ? Vec2{0, f * (h - 1)}
                                     : Vec2{w - 1.0, f * (h - 1)};
            Vec2 n{};
            if (!rig.camera.pixel_to_normalised(px, n))
                return false;
            Hit hit;
            if (!plane.intersect({0, 0, 0}, normalised(Vec3{n[0], n[1], 1}), 0, 1e9, hit))
                return false;
        }
    return true;
}

std::vector<Pose> session_poses(const Rig& rig, const SessionOptions& options) {
    if (options.poses < 1 || options.poses > 999)
        throw std::invalid_argument("session: poses must be in 1..999");
    if (!(options.near_mm > 0) || !(options.far_mm >= options.near_mm))
        throw std::invalid_argument("session: need 0 < near_mm <= far_mm");
    return options.kind == SessionKind::checkerboard ? checkerboard_poses(rig, options)
                                                     : plane_poses(rig, options);
}

Scene session_scene(const SessionOptions& options, const Pose& pose) {
    if (options.kind == SessionKind::checkerboard)
        return checkerboard_scene(pose, options.board);
    Scene scene;
    scene.add(std::make_unique<Plane>(pose, options.plane_width_mm, options.plane_height_mm,
                                      options.plane_albedo));
    return scene;
}

std::string session_board_yaml(const SessionOptions& options) {
    YAML::Emitter out;
    char comment[512];
    if (options.kind == SessionKind::checkerboard) {
        const CheckerboardSpec& b = options.board;
        std::snprintf(comment, sizeof comment,
                      "Simulated calibration session: printed checkerboard of %d x %d squares\n"
                      "(%d x %d inner corners, %g mm), %g mm white margin; the square\n"
                      "diagonally outside inner corner (0, 0) is black.",
                      b.inner_columns + 1, b.inner_rows + 1, b.inner_columns, b.inner_rows,
                      b.square_size, b.margin);
    } else {
        std::snprintf(comment, sizeof comment,
                      "Simulated session: flat white board of %g x %g mm filling the camera field.",
                      options.plane_width_mm, options.plane_height_mm);
    }
    out << YAML::Comment(comment);
    out << YAML::BeginMap;
    out << YAML::Key << "format" << YAML::Value << "fpp-board/1";
    if (options.kind == SessionKind::checkerboard) {
        const CheckerboardSpec& b = options.board;
        out << YAML::Key << "kind" << YAML::Value << "checkerboard";
        out << YAML::Key << "inner_corners" << YAML::Value << YAML::Flow << YAML::BeginSeq
            << b.inner_columns << b.inner_rows << YAML::EndSeq;
        out << YAML::Key << "square_size" << YAML::Value;
        yaml_emit::real(out, b.square_size);
    } else {
        out << YAML::Key << "kind" << YAML::Value << "plane";
    }
    out << YAML::EndMap;
    return yaml_emit::document(out);
}

// The capture's metadata for pose k (0-based): where the board was.
std::string session_pose_metadata_yaml(int k, const Pose& pose) {
    YAML::Emitter out;
    out << YAML::BeginMap;
    out << YAML::Key << "session_pose" << YAML::Value << k + 1;
    out << YAML::Key << "board_pose" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "centre_mm" << YAML::Value;
    yaml_emit::flow_reals(out, pose.centre.data(), pose.centre.size());
    out << YAML::Key << "rotation" << YAML::Value;
    yaml_emit::flow_reals(out, pose.R.data(), pose.R.size());
    out << YAML::EndMap << YAML::EndMap;
    return yaml_emit::document(out);
}

std::string session_pose_name(int k, int count) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "pose-%0*d", count >= 100 ? 3 : 2, k + 1);
    return buf;
}

void write_session(const std::filesystem::path& folder, const Rig& rig, const Sequence& sequence,
                   const SessionOptions& options, const SessionProgress& progress) {
    rig.validate();
    const std::vector<Pose> poses =
        session_poses(rig, options); // throws before anything is written
    if (std::filesystem::exists(folder))
        throw IoError(folder, "already exists; a session is never overwritten");
    write_folder_atomically(folder, [&](const std::filesystem::path& temp) {
        write_file_synced(temp / "board.yaml", session_board_yaml(options));
        const int count = static_cast<int>(poses.size());
        for (int k = 0; k < count; ++k) {
            const Pose& pose = poses[static_cast<std::size_t>(k)];
            const Scene scene = session_scene(options, pose);
            // Every pose gets its own noise.
            const std::uint64_t seed = options.seed * 1000003ULL + static_cast<std::uint64_t>(k);
            SimulatedCapture capture = simulate(rig, scene, sequence, seed);
            capture.manifest.metadata_yaml += session_pose_metadata_yaml(k, pose);
            write_simulated_capture(temp / session_pose_name(k, count), capture);
            if (progress)
                progress(k + 1, count);
        }
    });
}

} // namespace fpp::sim
