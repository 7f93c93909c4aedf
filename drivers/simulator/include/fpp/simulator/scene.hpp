#pragma once
// Scenes for the virtual scanner, in the camera frame (mm).
//
// Every shape is an opaque surface: a diffuse (Lambertian) term of the
// shape's albedo plus, optionally, a specular lobe (SpecularLobe) held by the
// scene per object. Poses map a shape's local frame to the camera frame:
// p_camera = centre + R p_local, with R from Euler angles in degrees as
// R = Rz(c) Ry(b) Rx(a) (fpp/lens_model.hpp).

#include "fpp/lens_model.hpp"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace fpp::sim {

struct Hit {
    double t = 0;      // ray parameter (distance along the unit direction), mm
    Vec3 point{};      // camera frame, mm
    Vec3 normal{};     // unit, facing the ray origin
    double albedo = 1; // diffuse reflectance in [0, 1]
    int object = -1;
};

// Specular reflection added to a shape's diffuse term: a normalised
// Blinn-Phong lobe. With l and v the unit directions from the surface point
// to the projector centre and to the camera centre, h = (l + v) / |l + v| and
// n the unit normal, the BRDF is
//   f = albedo / pi + specular (shininess + 8) / (8 pi) max(0, n.h)^shininess
// (sr^-1; the (n + 8) / (8 pi) factor keeps the lobe's reflected energy near
// `specular` whatever its width). The renderer multiplies pi f by the same
// projector light, incidence cosine and falloff as the diffuse term, so the
// fringe phase stays that of the projector pixel lighting the point; only the
// brightness changes (a highlight where n = h, many times the white level).
struct SpecularLobe {
    double specular = 0;  // ks in [0, 1]; albedo + ks <= 1; 0 = no lobe
    double shininess = 0; // Blinn-Phong exponent in [1, 1e5] when specular > 0

    bool active() const { return specular > 0; }
    // pi f_specular for cos_h = n.h: specular (shininess + 8) / 8 cos_h^shininess,
    // 0 for cos_h <= 0 or no lobe. Relative to a white Lambertian surface (pi f = 1).
    double relative_reflectance(double cos_h) const;
    // The exponent of a microfacet RMS slope (Beckmann roughness alpha):
    // 2 / alpha^2 - 2 (Walter et al. 2007), e.g. alpha 0.14 -> ~100.
    static double shininess_from_roughness(double roughness);
    // Throws std::invalid_argument for values out of the ranges above.
    void validate(double albedo) const;
};

class Shape {
public:
    virtual ~Shape() = default;
    // Nearest intersection with t in (tmin, tmax) of the ray o + t d (|d| = 1).
    virtual bool intersect(const Vec3& o, const Vec3& d, double tmin, double tmax,
                           Hit& hit) const = 0;
    // Mean albedo over a camera pixel's footprint on the surface: the
    // parallelogram hit.point + a dpdu + b dpdv, a, b in [-1/2, 1/2] (dpdu,
    // dpdv: surface displacement per camera pixel step). Textured shapes
    // override this so that printed edges are area-sampled as a real sensor
    // does; uniform shapes return hit.albedo.
    virtual double footprint_albedo(const Hit& hit, const Vec3& dpdu, const Vec3& dpdv) const {
        (void)dpdu;
        (void)dpdv;
        return hit.albedo;
    }
};

// Local-to-camera placement: p_camera = centre + R p_local.
struct Pose {
    Vec3 centre{};
    Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1};
    static Pose from_euler_deg(const Vec3& centre, double a, double b, double c);
    Vec3 to_camera(const Vec3& local) const;
    Vec3 to_local(const Vec3& camera) const;
};

// Finite rectangle of `width` x `height` mm in its local xy plane, centred on
// the pose's centre (normal = local z).
class Plane : public Shape {
public:
    Plane(const Pose& pose, double width, double height, double albedo);
    bool intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, Hit& hit) const override;
    const Pose& pose() const { return pose_; }

protected:
    // Local (x, y) of the hit of o + t d with the plane, without bounds checks.
    bool hit_plane(const Vec3& o, const Vec3& d, double tmin, double tmax, double& t, double& x,
                   double& y) const;
    Pose pose_;
    double half_width_, half_height_, albedo_;
};

// A printed checkerboard on a flat white board (local xy plane, normal local
// z). Inner corner (i, j), i < columns, j < rows, lies at local
// ((i - (columns-1)/2) s, (j - (rows-1)/2) s); the square whose top-left
// corner is inner corner (i-1, j-1) is black when i + j is even, so the four
// outermost squares at the corners of the pattern are black when columns and
// rows are both even. The board extends `margin` mm of white beyond the
// squares.
struct CheckerboardSpec {
    int inner_columns = 19;
    int inner_rows = 13;
    double square_size = 8.0; // mm (the paper's board)
    double margin = 10.0;     // mm of white around the squares
    double black_albedo = 0.05;
    double white_albedo = 0.9;
};

class Checkerboard : public Plane {
public:
    Checkerboard(const Pose& pose, const CheckerboardSpec& spec);
    bool intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, Hit& hit) const override;
    double footprint_albedo(const Hit& hit, const Vec3& dpdu, const Vec3& dpdv) const override;
    // Inner corners in the camera frame, row by row (j outer, i inner).
    std::vector<Vec3> inner_corners() const;
    const CheckerboardSpec& spec() const { return spec_; }
    // Albedo at local (x, y) (point sample).
    double albedo_at(double x, double y) const;

private:
    CheckerboardSpec spec_;
};

class Sphere : public Shape {
public:
    Sphere(const Vec3& centre, double radius, double albedo);
    bool intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, Hit& hit) const override;

private:
    Vec3 centre_;
    double radius_, albedo_;
};

// Closed finite cylinder: lateral surface of `radius` around the axis through
// `centre` along unit `axis`, from -length/2 to +length/2, with flat end caps.
class Cylinder : public Shape {
public:
    Cylinder(const Vec3& centre, const Vec3& axis, double radius, double length, double albedo);
    bool intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, Hit& hit) const override;

private:
    Vec3 centre_, axis_;
    double radius_, half_length_, albedo_;
};

// One smooth bump of a relief, with compact support (C2, polynomial: cheap
// to evaluate): amplitude (mm, negative for a hollow) * (1 - q)^3 where
// q = ((x - x0) / radius_x)^2 + ((y - y0) / radius_y)^2 < 1, and 0 outside.
// Close to a Gaussian of sigma = radius / 2.45.
struct ReliefBump {
    double x0 = 0, y0 = 0, amplitude = 0, radius_x = 1, radius_y = 1;
};

// A smooth height field over the rectangle |x| <= width/2, |y| <= height/2 of
// its local frame: the surface point over (x, y) is
// centre + x ex + y ey - h(x, y) ez (ex, ey, ez: columns of the pose's R),
// so heights rise toward the camera when R = I. The edges are open (a shell,
// like a mask). Intersection: the ray walks a grid of ~2 mm cells holding
// strict bounds of h and of |grad h|; it skips cells it passes above (or
// below), marches inside the others by steps of |w - h| / (local Lipschitz
// bound), which can never pass the first crossing, then brackets it and
// refines by safeguarded Newton to 1e-9 mm.
class Relief : public Shape {
public:
    Relief(const Pose& pose, double width, double height, std::vector<ReliefBump> bumps,
           double albedo);
    bool intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, Hit& hit) const override;
    double height_at(double x, double y) const;
    // Gradient (dh/dx, dh/dy).
    Vec2 gradient_at(double x, double y) const;
    // Camera-frame surface point over local (x, y).
    Vec3 surface_point(double x, double y) const;
    double slope_bound() const { return slope_bound_; }

    // A face-like mask: forehead, brows, eye hollows, nose, cheeks, lips, chin
    // (width 160 mm, height 220 mm, heights 0..~55 mm).
    static std::vector<ReliefBump> face_bumps();

private:
    // Height, and optionally gradient, at local (x, y).
    double eval(double x, double y, double* gx, double* gy) const;
    // Strict bounds of h and |grad h| over one cell of a uniform grid on the
    // rectangle: marching skips cells the ray passes above (or below) and
    // steps by the cell's own slope bound elsewhere.
    struct Cell {
        double h_min, h_max, slope;
    };
    // Bumps with reciprocal radii (the evaluation is the hot loop).
    struct ScaledBump {
        double x0, y0, amplitude, inv_rx, inv_ry;
    };
    static double eval_range(const ScaledBump* begin, const ScaledBump* end, double x, double y,
                             double* gx, double* gy);
    // intersect()'s stages. A ray in local coordinates (x, y, w), w = -z_local
    // (the height direction); along it f(t) = w(t) - h(x(t), y(t)).
    struct LocalRay {
        double ox, oy, ow, dx, dy, dw;
    };
    // The first sign change of f, in [a, b], with the bumps of its cell.
    struct Bracket {
        double a, fa, b, fb;
        const ScaledBump* bumps_begin;
        const ScaledBump* bumps_end;
    };
    LocalRay local_ray(const Vec3& o, const Vec3& d) const;
    // Narrows [t0, t1] to the ray's stretch inside the bounding box; false if none.
    bool clip_to_box(const LocalRay& r, double& t0, double& t1) const;
    // f(t) over the bumps [begin, end).
    static double height_gap(const LocalRay& r, const ScaledBump* begin, const ScaledBump* end,
                             double t);
    // Ray parameter (at most t1) where the ray leaves the cell holding
    // parameter `at`, which goes to (cx, cy).
    double cell_exit(const LocalRay& r, double at, double t1, int& cx, int& cy) const;
    // Walks the cells from t (f(t) = ft, not 0) to t1; false if f keeps its sign.
    bool bracket_crossing(const LocalRay& r, double t, double ft, double t1, Bracket& out) const;
    // The root inside a bracket (safeguarded Newton).
    static double refine_crossing(const LocalRay& r, Bracket br);
    // The hit at parameter t; false outside the rectangle.
    bool surface_hit(const Vec3& o, const Vec3& d, const LocalRay& r, double t, Hit& hit) const;
    std::vector<ScaledBump> scaled_;
    // Per cell, the bumps whose support overlaps it (the others are exactly
    // 0 there): cell i owns cell_bumps_[cell_offset_[i] .. cell_offset_[i+1]).
    std::vector<ScaledBump> cell_bumps_;
    std::vector<std::size_t> cell_offset_;
    Pose pose_;
    double half_width_, half_height_, albedo_;
    std::vector<ReliefBump> bumps_;
    int cells_x_ = 1, cells_y_ = 1;
    double cell_w_ = 1, cell_h_ = 1;
    std::vector<Cell> cells_;
    double h_min_ = 0, h_max_ = 0; // bounds of h over the rectangle
    double slope_bound_ = 0;       // upper bound of |grad h| over the rectangle
};

// Objects of a scene: shapes, numbered in the order added (Hit::object),
// each with a name (labels for per-part figures: Renderer::truth_object) and a
// specular lobe. Several objects may share a name (a part made of shapes).
class Scene {
public:
    // Adds `shape` as object size(). An empty `name` becomes "object<i>".
    // Throws std::invalid_argument for a null shape or an invalid lobe.
    void add(std::unique_ptr<Shape> shape, std::string name = {},
             const SpecularLobe& specular = {});
    bool intersect(const Vec3& o, const Vec3& d, Hit& hit) const;   // nearest
    bool occluded(const Vec3& o, const Vec3& d, double tmax) const; // any hit in (eps, tmax)
    std::size_t size() const { return shapes_.size(); }
    const Shape& shape(std::size_t i) const { return *shapes_[i]; }
    const std::string& object_name(std::size_t i) const { return names_.at(i); }
    const SpecularLobe& specular(std::size_t i) const { return specular_.at(i); }

    // Smallest ray parameter that counts as a hit (mm): rays start on surfaces.
    static constexpr double kEpsilon = 1e-7;

private:
    std::vector<std::unique_ptr<Shape>> shapes_;
    std::vector<std::string> names_;
    std::vector<SpecularLobe> specular_;
};

// Two spheres of `radius` whose centres are `distance` mm apart, symmetric
// about `centre` along unit `axis` (a ball bar without its rod), both named
// `name` (see Scene::add) with lobe `specular`.
void add_ball_bar(Scene& scene, const Vec3& centre, const Vec3& axis, double distance,
                  double radius, double albedo, const std::string& name = {},
                  const SpecularLobe& specular = {});

// A scene holding a single checkerboard at `pose` (calibration poses).
Scene checkerboard_scene(const Pose& pose, const CheckerboardSpec& spec = {});

// Built-in scenes: "plane", "inclined-plane", "checkerboard", "cylinder",
// "sphere", "ball-bar", "relief", "composite" (default: relief and a sphere
// over a background plane, with occlusions and projector shadows), and
// "hdr-parts" (the same as board/sim/scenes/hdr-parts.yaml: objects
// "background", a matte white plate at 540 mm; "white", a matte white sphere;
// "dark", a rubber-like dome of albedo 0.03; "metal", a polished cylinder of
// albedo 0.2 with a specular lobe whose highlight clips an 8-bit camera at
// the exposure that puts the white part near 200 DN, and does not at 1/8 of
// it). All lie in the paper's calibration volume (Z from 400 to 560 mm;
// planes at ~480 mm). Throws std::invalid_argument for an unknown name.
Scene named_scene(const std::string& name);
std::vector<std::string> named_scene_names();
// A scene from a YAML file (list of shapes); throws InputError. Schema: see
// board/sim/scenes/composite.yaml. Per shape, optional `name` (default
// "object<i>") and either `albedo` or `material: {albedo, specular,
// shininess | roughness}` (SpecularLobe; roughness alpha in [0.005, 0.8]
// gives shininess 2 / alpha^2 - 2).
Scene load_scene(const std::filesystem::path& path);
// A name from named_scene_names() or a path to a YAML file.
Scene scene_from_argument(const std::string& name_or_path);

} // namespace fpp::sim
