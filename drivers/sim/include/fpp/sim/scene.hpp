#pragma once
// Scenes for the virtual scanner, in the camera frame (mm).

#include "fpp/lens_model.hpp"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace fpp::sim {

struct Hit {
    double t = 0;     // ray parameter (distance along the unit direction), mm
    Vec3 point{};     // camera frame, mm
    Vec3 normal{};    // unit, facing the ray origin
    double albedo = 1; // diffuse reflectance in [0, 1]
    int object = -1;
};

class Shape {
public:
    virtual ~Shape() = default;
    // Nearest intersection with t in (tmin, tmax) of the ray o + t d (|d| = 1).
    virtual bool intersect(const Vec3& o, const Vec3& d, double tmin, double tmax,
                           Hit& hit) const = 0;
};

class Scene {
public:
    void add(std::unique_ptr<Shape> shape);
    bool intersect(const Vec3& o, const Vec3& d, Hit& hit) const; // nearest
    bool occluded(const Vec3& o, const Vec3& d, double tmax) const; // any hit in (eps, tmax)
    std::size_t size() const { return shapes_.size(); }

private:
    std::vector<std::unique_ptr<Shape>> shapes_;
};

// Built-in scenes: "plane", "inclined-plane", "checkerboard", "cylinder",
// "sphere", "ball-bar", "relief", "composite" (default: relief and a sphere
// over a background plane, with occlusions and projector shadows).
Scene named_scene(const std::string& name);
std::vector<std::string> named_scene_names();
// A scene from a YAML file (list of shapes); throws InputError.
Scene load_scene(const std::filesystem::path& path);
// A name from named_scene_names() or a path to a YAML file.
Scene scene_from_argument(const std::string& name_or_path);

} // namespace fpp::sim
