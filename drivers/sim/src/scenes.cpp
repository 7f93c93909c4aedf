// Built-in scenes and scene YAML files (format fpp-scene/1).

#include "fpp/sim/scene.hpp"

#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"
#include "vec_math.hpp"

#include <stdexcept>

namespace fpp::sim {

using yaml_fields::child;
using yaml_fields::item;
using yaml_fields::Reader;

namespace {

constexpr const char* kSceneFormat = "fpp-scene/1";

// Parts of the default composite, shared with board/sim/scenes/composite.yaml.
constexpr double kRelief[3] = {-45, 5, 505};
constexpr double kSphere[3] = {80, 25, 450};
constexpr double kSphereRadius = 38;

Scene composite_scene() {
    Scene s;
    s.add(std::make_unique<Plane>(Pose{{0, 0, 540}, {1, 0, 0, 0, 1, 0, 0, 0, 1}}, 420, 330, 0.85));
    s.add(std::make_unique<Relief>(
        Pose{{kRelief[0], kRelief[1], kRelief[2]}, {1, 0, 0, 0, 1, 0, 0, 0, 1}}, 160, 220,
        Relief::face_bumps(), 0.8));
    s.add(std::make_unique<Sphere>(Vec3{kSphere[0], kSphere[1], kSphere[2]}, kSphereRadius, 0.9));
    return s;
}

// ---- YAML ------------------------------------------------------------------

Pose read_pose(const Reader& in, const YAML::Node& node, const std::string& field) {
    Pose pose;
    pose.centre = in.real_array<3>(in.require(node, field, "centre"), child(field, "centre"));
    const YAML::Node e = node["euler_deg"];
    if (e.IsDefined()) {
        const auto a = in.real_array<3>(e, child(field, "euler_deg"));
        pose.R = rotation_from_euler_deg(a[0], a[1], a[2]);
    }
    return pose;
}

double read_albedo(const Reader& in, const YAML::Node& node, const std::string& field,
                   const char* key) {
    const YAML::Node value = in.require(node, field, key);
    const double a = in.real_value(value, child(field, key));
    if (!(a >= 0 && a <= 1))
        in.fail(value, child(field, key), "must be in [0, 1]");
    return a;
}

double read_positive(const Reader& in, const YAML::Node& node, const std::string& field,
                     const char* key) {
    const YAML::Node value = in.require(node, field, key);
    const double v = in.real_value(value, child(field, key));
    if (!(v > 0))
        in.fail(value, child(field, key), "must be positive");
    return v;
}

Vec3 read_direction(const Reader& in, const YAML::Node& node, const std::string& field,
                    const char* key) {
    const YAML::Node value = in.require(node, field, key);
    const Vec3 a = in.real_array<3>(value, child(field, key));
    if (!(vec::norm(a) > 1e-12))
        in.fail(value, child(field, key), "must be a non-zero vector");
    return vec::normalised(a);
}

std::array<double, 2> read_size(const Reader& in, const YAML::Node& node,
                                const std::string& field) {
    const YAML::Node value = in.require(node, field, "size");
    const auto s = in.real_array<2>(value, child(field, "size"));
    if (!(s[0] > 0) || !(s[1] > 0))
        in.fail(value, child(field, "size"), "must be positive");
    return s;
}

void read_shape(const Reader& in, const YAML::Node& node, const std::string& field, Scene& scene) {
    if (!node.IsMap())
        in.fail(node, field, "expected a map with a `type`");
    const YAML::Node type_node = in.require(node, field, "type");
    const std::string type = in.string_value(type_node, child(field, "type"));
    if (type == "plane") {
        in.expect_map(node, field, {"type", "centre", "euler_deg", "size", "albedo"});
        const auto size = read_size(in, node, field);
        scene.add(std::make_unique<Plane>(read_pose(in, node, field), size[0], size[1],
                                          read_albedo(in, node, field, "albedo")));
    } else if (type == "checkerboard") {
        in.expect_map(node, field,
                      {"type", "centre", "euler_deg", "inner_corners", "square_size", "margin",
                       "black_albedo", "white_albedo"});
        CheckerboardSpec spec;
        const std::string cfield = child(field, "inner_corners");
        const YAML::Node corners = in.require(node, field, "inner_corners");
        if (!corners.IsSequence() || corners.size() != 2)
            in.fail(corners, cfield, "expected [columns, rows]");
        spec.inner_columns = in.int_value(corners[0], item(cfield, 0));
        spec.inner_rows = in.int_value(corners[1], item(cfield, 1));
        if (spec.inner_columns < 2 || spec.inner_rows < 2 || spec.inner_columns > 1000 ||
            spec.inner_rows > 1000)
            in.fail(corners, cfield, "must be 2..1000 each");
        spec.square_size = read_positive(in, node, field, "square_size");
        spec.margin = in.real_value_or(node, field, "margin", spec.margin);
        if (!(spec.margin >= 0))
            in.fail(node["margin"], child(field, "margin"), "must be >= 0");
        spec.black_albedo = read_albedo(in, node, field, "black_albedo");
        spec.white_albedo = read_albedo(in, node, field, "white_albedo");
        scene.add(std::make_unique<Checkerboard>(read_pose(in, node, field), spec));
    } else if (type == "sphere") {
        in.expect_map(node, field, {"type", "centre", "radius", "albedo"});
        scene.add(std::make_unique<Sphere>(
            in.real_array<3>(in.require(node, field, "centre"), child(field, "centre")),
            read_positive(in, node, field, "radius"), read_albedo(in, node, field, "albedo")));
    } else if (type == "cylinder") {
        in.expect_map(node, field, {"type", "centre", "axis", "radius", "length", "albedo"});
        scene.add(std::make_unique<Cylinder>(
            in.real_array<3>(in.require(node, field, "centre"), child(field, "centre")),
            read_direction(in, node, field, "axis"), read_positive(in, node, field, "radius"),
            read_positive(in, node, field, "length"), read_albedo(in, node, field, "albedo")));
    } else if (type == "ball_bar") {
        in.expect_map(node, field, {"type", "centre", "axis", "distance", "radius", "albedo"});
        const double distance = read_positive(in, node, field, "distance");
        const double radius = read_positive(in, node, field, "radius");
        if (!(distance > 2 * radius))
            in.fail(node["distance"], child(field, "distance"), "must exceed the sphere diameter");
        add_ball_bar(scene,
                     in.real_array<3>(in.require(node, field, "centre"), child(field, "centre")),
                     read_direction(in, node, field, "axis"), distance, radius,
                     read_albedo(in, node, field, "albedo"));
    } else if (type == "relief") {
        in.expect_map(node, field, {"type", "centre", "euler_deg", "size", "albedo", "bumps"});
        const auto size = read_size(in, node, field);
        std::vector<ReliefBump> bumps = Relief::face_bumps();
        const YAML::Node b = node["bumps"];
        if (b.IsDefined()) {
            const std::string bfield = child(field, "bumps");
            if (!b.IsSequence() || b.size() == 0 || b.size() > 1000)
                in.fail(b, bfield, "expected a list of [x0, y0, amplitude, radius_x, radius_y]");
            bumps.clear();
            for (std::size_t i = 0; i < b.size(); ++i) {
                const std::string bf = item(bfield, i);
                const auto v = in.real_array<5>(b[i], bf);
                if (!(v[3] > 0) || !(v[4] > 0))
                    in.fail(b[i], bf, "radii must be positive");
                bumps.push_back({v[0], v[1], v[2], v[3], v[4]});
            }
        }
        scene.add(std::make_unique<Relief>(read_pose(in, node, field), size[0], size[1],
                                           std::move(bumps),
                                           read_albedo(in, node, field, "albedo")));
    } else {
        in.fail(type_node, child(field, "type"),
                "unknown shape type '" + type +
                    "' (plane, checkerboard, sphere, cylinder, ball_bar, relief)");
    }
}

} // namespace

Scene checkerboard_scene(const Pose& pose, const CheckerboardSpec& spec) {
    Scene s;
    s.add(std::make_unique<Checkerboard>(pose, spec));
    return s;
}

std::vector<std::string> named_scene_names() {
    return {"plane",  "inclined-plane", "checkerboard", "cylinder",
            "sphere", "ball-bar",       "relief",       "composite"};
}

Scene named_scene(const std::string& name) {
    const Mat3 I{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Scene s;
    if (name == "plane") {
        // Fills the camera field (about 284 x 213 mm at 480 mm).
        s.add(std::make_unique<Plane>(Pose{{0, 0, 480}, I}, 400, 320, 0.9));
    } else if (name == "inclined-plane") {
        // Depth across the field from about 415 to 555 mm.
        s.add(std::make_unique<Plane>(Pose::from_euler_deg({0, 0, 480}, 8, -20, 0), 420, 340, 0.9));
    } else if (name == "checkerboard") {
        return checkerboard_scene(Pose::from_euler_deg({0, 0, 480}, 12, -18, 3));
    } else if (name == "cylinder") {
        s.add(std::make_unique<Cylinder>(Vec3{0, 0, 500}, Vec3{0, 1, 0}, 60, 240, 0.85));
    } else if (name == "sphere") {
        s.add(std::make_unique<Sphere>(Vec3{0, 0, 480}, 60, 0.9));
    } else if (name == "ball-bar") {
        add_ball_bar(s, {0, 0, 480}, {1, 0.2, 0.3}, 150, 15, 0.85);
    } else if (name == "relief") {
        s.add(std::make_unique<Relief>(Pose{{0, 0, 500}, I}, 160, 220, Relief::face_bumps(), 0.85));
    } else if (name == "composite") {
        return composite_scene();
    } else {
        throw std::invalid_argument("unknown scene '" + name + "'");
    }
    return s;
}

Scene load_scene(const std::filesystem::path& path) {
    const Reader in(path);
    const YAML::Node root = in.load_file();
    if (!root.IsMap())
        in.fail(root, "(top level)", std::string("expected a map with format: ") + kSceneFormat);
    in.expect_map(root, "", {"format", "shapes"});
    const YAML::Node format_node = in.require(root, "", "format");
    const std::string format = in.string_value(format_node, "format");
    if (format != kSceneFormat)
        in.fail(format_node, "format",
                "unknown format '" + format + "' (expected " + kSceneFormat + ")");
    const YAML::Node shapes = in.require(root, "", "shapes");
    if (!shapes.IsSequence() || shapes.size() == 0)
        in.fail(shapes, "shapes", "expected a non-empty list");
    Scene scene;
    for (std::size_t i = 0; i < shapes.size(); ++i) {
        const std::string field = item("shapes", i);
        try {
            read_shape(in, shapes[i], field, scene);
        } catch (const std::invalid_argument& e) { // a shape's own consistency check
            in.fail(shapes[i], field, e.what());
        }
    }
    return scene;
}

Scene scene_from_argument(const std::string& name_or_path) {
    for (const auto& n : named_scene_names())
        if (n == name_or_path)
            return named_scene(n);
    return load_scene(name_or_path);
}

} // namespace fpp::sim
