// Built-in scenes and scene YAML files (format fpp-scene/1).

#include "fpp/simulator/scene.hpp"

#include "fpp/error.hpp"
#include "fpp/vec3.hpp"
#include "fpp/yaml_fields.hpp"

#include <algorithm>
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
    s.add(std::make_unique<Plane>(Pose{{0, 0, 540}, {1, 0, 0, 0, 1, 0, 0, 0, 1}}, 420, 330, 0.85),
          "background");
    s.add(std::make_unique<Relief>(
              Pose{{kRelief[0], kRelief[1], kRelief[2]}, {1, 0, 0, 0, 1, 0, 0, 0, 1}}, 160, 220,
              Relief::face_bumps(), 0.8),
          "relief");
    s.add(std::make_unique<Sphere>(Vec3{kSphere[0], kSphere[1], kSphere[2]}, kSphereRadius, 0.9),
          "sphere");
    return s;
}

// The HDR scene, shared with board/sim/scenes/hdr-parts.yaml. Radiometry on
// the paper rig (white level 240 DN) at its nominal exposure: the white
// sphere peaks near 216 DN, the dark dome near 7 DN, the metal cylinder's
// diffuse part near 45 DN and its highlight (where its normal meets the half
// vector, about y = 50 mm) near 1600 DN, i.e. it clips an 8-bit camera over
// a band along the cylinder and stays below full scale at 1/8 of the exposure.
constexpr double kHdrWhiteCentre[3] = {-70, -42, 480};
constexpr double kHdrWhiteRadius = 36;
constexpr double kHdrWhiteAlbedo = 0.9;
constexpr double kHdrDarkCentre[3] = {-62, 55, 505};
constexpr double kHdrDarkSize[2] = {124, 84};
constexpr ReliefBump kHdrDarkDome{0, 0, 24, 60, 40};
constexpr double kHdrDarkAlbedo = 0.03;
constexpr double kHdrMetalCentre[3] = {72, 5, 470};
constexpr double kHdrMetalRadius = 28;
constexpr double kHdrMetalLength = 170;
constexpr double kHdrMetalAlbedo = 0.2;
constexpr SpecularLobe kHdrMetalLobe{0.5, 100};

Scene hdr_parts_scene() {
    const Mat3 I{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Scene s;
    s.add(std::make_unique<Plane>(Pose{{0, 0, 540}, I}, 420, 330, 0.85), "background");
    s.add(std::make_unique<Sphere>(Vec3{kHdrWhiteCentre[0], kHdrWhiteCentre[1], kHdrWhiteCentre[2]},
                                   kHdrWhiteRadius, kHdrWhiteAlbedo),
          "white");
    s.add(std::make_unique<Relief>(
              Pose{{kHdrDarkCentre[0], kHdrDarkCentre[1], kHdrDarkCentre[2]}, I}, kHdrDarkSize[0],
              kHdrDarkSize[1], std::vector<ReliefBump>{kHdrDarkDome}, kHdrDarkAlbedo),
          "dark");
    s.add(std::make_unique<Cylinder>(
              Vec3{kHdrMetalCentre[0], kHdrMetalCentre[1], kHdrMetalCentre[2]}, Vec3{0, 1, 0},
              kHdrMetalRadius, kHdrMetalLength, kHdrMetalAlbedo),
          "metal", kHdrMetalLobe);
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

// What every shape may carry besides its geometry: `name`, and its albedo
// and specular lobe from either `albedo` or `material`.
struct Surface {
    std::string name;
    double albedo = 0;
    SpecularLobe specular;
};

std::string read_name(const Reader& in, const YAML::Node& node, const std::string& field) {
    const YAML::Node value = node["name"];
    if (!value.IsDefined())
        return {};
    const std::string name = in.string_value(value, child(field, "name"));
    if (name.empty() || name.size() > 64)
        in.fail(value, child(field, "name"), "must be 1 to 64 characters");
    for (const char c : name)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
            in.fail(value, child(field, "name"), "must not hold control characters");
    return name;
}

// `material: {albedo, specular, shininess | roughness}` (albedo only for
// shapes that have one); the energy bound albedo + specular <= 1 is checked
// by check_energy once the albedo is known.
SpecularLobe read_lobe(const Reader& in, const YAML::Node& material, const std::string& mfield) {
    SpecularLobe lobe;
    const YAML::Node ks = material["specular"], shininess = material["shininess"],
                     roughness = material["roughness"];
    if (ks.IsDefined()) {
        lobe.specular = in.real_value(ks, child(mfield, "specular"));
        if (!(lobe.specular >= 0 && lobe.specular <= 1))
            in.fail(ks, child(mfield, "specular"), "must be in [0, 1]");
    }
    if (shininess.IsDefined() && roughness.IsDefined())
        in.fail(roughness, child(mfield, "roughness"), "give `shininess` or `roughness`, not both");
    const YAML::Node width = shininess.IsDefined() ? shininess : roughness;
    const char* width_key = shininess.IsDefined() ? "shininess" : "roughness";
    if (width.IsDefined() && !ks.IsDefined())
        in.fail(width, child(mfield, width_key), "needs `specular` (the lobe's strength)");
    if (shininess.IsDefined()) {
        lobe.shininess = in.real_value(shininess, child(mfield, "shininess"));
        if (!(lobe.shininess >= 1 && lobe.shininess <= 1e5))
            in.fail(shininess, child(mfield, "shininess"), "must be in [1, 100000]");
    } else if (roughness.IsDefined()) {
        const double alpha = in.real_value(roughness, child(mfield, "roughness"));
        if (!(alpha >= 0.005 && alpha <= 0.8))
            in.fail(roughness, child(mfield, "roughness"), "must be in [0.005, 0.8]");
        lobe.shininess = SpecularLobe::shininess_from_roughness(alpha);
    } else if (lobe.specular > 0) {
        in.fail(material, mfield, "a specular lobe needs `shininess` or `roughness`");
    }
    return lobe;
}

void check_energy(const Reader& in, const YAML::Node& node, const std::string& field, double albedo,
                  const SpecularLobe& lobe) {
    if (albedo + lobe.specular > 1 + 1e-12)
        in.fail(node["material"]["specular"], child(child(field, "material"), "specular"),
                "albedo + specular must not exceed 1 (no more light out than in)");
}

// `has_albedo`: the shape has one uniform albedo (all but the checkerboard,
// whose albedos are its own fields).
Surface read_surface(const Reader& in, const YAML::Node& node, const std::string& field,
                     bool has_albedo) {
    Surface s;
    s.name = read_name(in, node, field);
    const YAML::Node material = node["material"];
    if (!material.IsDefined()) {
        if (has_albedo && !node["albedo"].IsDefined())
            in.fail(node, child(field, "albedo"), "missing field (or material: {albedo: ...})");
        if (has_albedo)
            s.albedo = read_albedo(in, node, field, "albedo");
        return s;
    }
    const std::string mfield = child(field, "material");
    if (has_albedo)
        in.expect_map(material, mfield, {"albedo", "specular", "shininess", "roughness"});
    else
        in.expect_map(material, mfield, {"specular", "shininess", "roughness"});
    s.specular = read_lobe(in, material, mfield);
    if (has_albedo) {
        const YAML::Node plain = node["albedo"];
        if (plain.IsDefined())
            in.fail(plain, child(field, "albedo"), "given twice: here and as material.albedo");
        s.albedo = read_albedo(in, material, mfield, "albedo");
        check_energy(in, node, field, s.albedo, s.specular);
    }
    return s;
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
        in.expect_map(node, field,
                      {"type", "name", "centre", "euler_deg", "size", "albedo", "material"});
        const auto size = read_size(in, node, field);
        const Surface surface = read_surface(in, node, field, true);
        scene.add(
            std::make_unique<Plane>(read_pose(in, node, field), size[0], size[1], surface.albedo),
            surface.name, surface.specular);
    } else if (type == "checkerboard") {
        in.expect_map(node, field,
                      {"type", "name", "centre", "euler_deg", "inner_corners", "square_size",
                       "margin", "black_albedo", "white_albedo", "material"});
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
        const Surface surface = read_surface(in, node, field, false);
        check_energy(in, node, field, std::max(spec.black_albedo, spec.white_albedo),
                     surface.specular);
        scene.add(std::make_unique<Checkerboard>(read_pose(in, node, field), spec), surface.name,
                  surface.specular);
    } else if (type == "sphere") {
        in.expect_map(node, field, {"type", "name", "centre", "radius", "albedo", "material"});
        const Vec3 centre =
            in.real_array<3>(in.require(node, field, "centre"), child(field, "centre"));
        const double radius = read_positive(in, node, field, "radius");
        const Surface surface = read_surface(in, node, field, true);
        scene.add(std::make_unique<Sphere>(centre, radius, surface.albedo), surface.name,
                  surface.specular);
    } else if (type == "cylinder") {
        in.expect_map(node, field,
                      {"type", "name", "centre", "axis", "radius", "length", "albedo", "material"});
        const Vec3 centre =
            in.real_array<3>(in.require(node, field, "centre"), child(field, "centre"));
        const Vec3 axis = read_direction(in, node, field, "axis");
        const double radius = read_positive(in, node, field, "radius");
        const double length = read_positive(in, node, field, "length");
        const Surface surface = read_surface(in, node, field, true);
        scene.add(std::make_unique<Cylinder>(centre, axis, radius, length, surface.albedo),
                  surface.name, surface.specular);
    } else if (type == "ball_bar") {
        in.expect_map(
            node, field,
            {"type", "name", "centre", "axis", "distance", "radius", "albedo", "material"});
        const double distance = read_positive(in, node, field, "distance");
        const double radius = read_positive(in, node, field, "radius");
        if (!(distance > 2 * radius))
            in.fail(node["distance"], child(field, "distance"), "must exceed the sphere diameter");
        const Vec3 centre =
            in.real_array<3>(in.require(node, field, "centre"), child(field, "centre"));
        const Vec3 axis = read_direction(in, node, field, "axis");
        const Surface surface = read_surface(in, node, field, true);
        add_ball_bar(scene, centre, axis, distance, radius, surface.albedo, surface.name,
                     surface.specular);
    } else if (type == "relief") {
        in.expect_map(
            node, field,
            {"type", "name", "centre", "euler_deg", "size", "albedo", "material", "bumps"});
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
        const Surface surface = read_surface(in, node, field, true);
        scene.add(std::make_unique<Relief>(read_pose(in, node, field), size[0], size[1],
                                           std::move(bumps), surface.albedo),
                  surface.name, surface.specular);
    } else {
        in.fail(type_node, child(field, "type"),
                "unknown shape type '" + type +
                    "' (plane, checkerboard, sphere, cylinder, ball_bar, relief)");
    }
}

} // namespace

Scene checkerboard_scene(const Pose& pose, const CheckerboardSpec& spec) {
    Scene s;
    s.add(std::make_unique<Checkerboard>(pose, spec), "checkerboard");
    return s;
}

std::vector<std::string> named_scene_names() {
    return {"plane",    "inclined-plane", "checkerboard", "cylinder", "sphere",
            "ball-bar", "relief",         "composite",    "hdr-parts"};
}

Scene named_scene(const std::string& name) {
    const Mat3 I{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Scene s;
    if (name == "plane") {
        // Fills the camera field (about 284 x 213 mm at 480 mm).
        s.add(std::make_unique<Plane>(Pose{{0, 0, 480}, I}, 400, 320, 0.9), "plane");
    } else if (name == "inclined-plane") {
        // Depth across the field from about 415 to 555 mm.
        s.add(std::make_unique<Plane>(Pose::from_euler_deg({0, 0, 480}, 8, -20, 0), 420, 340, 0.9),
              "plane");
    } else if (name == "checkerboard") {
        return checkerboard_scene(Pose::from_euler_deg({0, 0, 480}, 12, -18, 3));
    } else if (name == "cylinder") {
        s.add(std::make_unique<Cylinder>(Vec3{0, 0, 500}, Vec3{0, 1, 0}, 60, 240, 0.85),
              "cylinder");
    } else if (name == "sphere") {
        s.add(std::make_unique<Sphere>(Vec3{0, 0, 480}, 60, 0.9), "sphere");
    } else if (name == "ball-bar") {
        add_ball_bar(s, {0, 0, 480}, {1, 0.2, 0.3}, 150, 15, 0.85, "ball");
    } else if (name == "relief") {
        s.add(std::make_unique<Relief>(Pose{{0, 0, 500}, I}, 160, 220, Relief::face_bumps(), 0.85),
              "relief");
    } else if (name == "composite") {
        return composite_scene();
    } else if (name == "hdr-parts") {
        return hdr_parts_scene();
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
