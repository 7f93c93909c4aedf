// A second camera for the virtual scanner (fpp/simulator/camera_pair_rig.hpp).

#include "fpp/simulator/camera_pair_rig.hpp"

#include "fpp/vec3.hpp"

#include <stdexcept>
#include <string>
#include <utility>

namespace fpp::sim {

namespace {

using namespace vec;

// One object of a scene, moved rigidly: p_new = R p_old + T. Rays are taken
// back into the object's own frame (lengths are kept, so t is too) and hits
// brought forward.
class MovedShape : public Shape {
public:
    MovedShape(std::shared_ptr<const Scene> scene, std::size_t index, const Mat3& R, const Vec3& T)
        : scene_(std::move(scene)), shape_(&scene_->shape(index)), R_(R), Rt_(transpose(R)), T_(T) {
    }

    bool intersect(const Vec3& o, const Vec3& d, double tmin, double tmax,
                   Hit& hit) const override {
        if (!shape_->intersect(to_old(o), mul(Rt_, d), tmin, tmax, hit))
            return false;
        hit.point = add(mul(R_, hit.point), T_);
        hit.normal = mul(R_, hit.normal);
        return true;
    }

    double footprint_albedo(const Hit& hit, const Vec3& dpdu, const Vec3& dpdv) const override {
        Hit old = hit;
        old.point = to_old(hit.point);
        old.normal = mul(Rt_, hit.normal);
        return shape_->footprint_albedo(old, mul(Rt_, dpdu), mul(Rt_, dpdv));
    }

private:
    Vec3 to_old(const Vec3& p) const { return mul(Rt_, sub(p, T_)); }

    std::shared_ptr<const Scene> scene_; // keeps shape_ alive
    const Shape* shape_;
    Mat3 R_, Rt_;
    Vec3 T_;
};

} // namespace

Rig second_camera_rig(const Rig& first, const LensModel& camera, Size camera_size, const Mat3& R,
                      const Vec3& T) {
    // X_p = R_1p X_1 + t_1p and X_1 = R^T (X_2 - T) give
    // X_p = (R_1p R^T) X_2 + (t_1p - R_1p R^T T).
    Rig second = first;
    second.name = first.name + "-second-camera";
    second.camera = camera;
    second.camera_size = camera_size;
    second.R = mul(first.R, transpose(R));
    second.t = sub(first.t, mul(second.R, T));
    return second;
}

CameraPairRig binocular_rig(const Rig& first, double baseline_mm, double converge_mm) {
    if (!(baseline_mm > 0) || !(converge_mm > 0))
        throw std::invalid_argument("binocular_rig: baseline and convergence distance must be > 0");
    const Vec3 centre{baseline_mm, 0, 0};
    // Rows of R are the second camera's axes in the first camera's frame:
    // z toward the target, x = y_1 x z (level), y = z x x.
    const Vec3 z = normalised(sub(Vec3{0, 0, converge_mm}, centre));
    const Vec3 x = normalised(cross(Vec3{0, 1, 0}, z));
    const Vec3 y = cross(z, x);
    CameraPairRig pair;
    pair.R = {x[0], x[1], x[2], y[0], y[1], y[2], z[0], z[1], z[2]};
    pair.T = scale(mul(pair.R, centre), -1.0);
    LensModel lens = first.camera;
    lens.fu *= 1.004;
    lens.fv *= 1.004;
    lens.cu += 9.0;
    lens.cv -= 6.0;
    lens.k1 -= 0.01;
    pair.first = first;
    pair.second = second_camera_rig(first, lens, first.camera_size, pair.R, pair.T);
    return pair;
}

CameraPairRig binned(const CameraPairRig& pair, int factor) {
    CameraPairRig out = pair;
    out.first = pair.first.binned_camera(factor);
    out.second = pair.second.binned_camera(factor);
    return out;
}

Scene scene_seen_from(std::shared_ptr<const Scene> scene, const Mat3& R, const Vec3& T) {
    if (!scene)
        throw std::invalid_argument("scene_seen_from: null scene");
    Scene moved;
    for (std::size_t i = 0; i < scene->size(); ++i)
        moved.add(std::make_unique<MovedShape>(scene, i, R, T), scene->object_name(i),
                  scene->specular(i));
    return moved;
}

} // namespace fpp::sim
