#pragma once
// The virtual scanner's ball bar for fpp-calib verify's tests: two 30 mm
// spheres on a 10 mm rod, the rod on a post, a wall behind (as
// board/sim/scenes/ball-bar-on-stand.yaml), as a scene YAML placed at one of
// seven positions after VDI/VDE 2634-2 (across the view, tilted in depth
// both ways, diagonals, steep in the image) within the paper rig's volume:
// sphere centres between Z 430 and 530 mm. Camera frame, mm. Header-only.

#include "fpp/lens_model.hpp"

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace fpp::test {

inline constexpr double kBallDiameterMm = 30, kBallBarLengthMm = 150;

struct BallBarPlacement {
    Vec3 centre{};                         // the bar's middle
    Vec3 axis{};                           // its direction (any length)
    double length = kBallBarLengthMm;      // the true centre distance
    std::string material = "albedo: 0.85"; // or "material: {...}" (fpp-scene/1)
};

// The seven positions.
inline const std::vector<BallBarPlacement>& vdi_ball_bar_positions() {
    static const std::vector<BallBarPlacement> positions = {
        {{0, -10, 480}, {1, 0, 0}},        {{0, -5, 480}, {0.87, 0, 0.5}},
        {{0, -5, 480}, {-0.87, 0, 0.5}},   {{0, -15, 480}, {0.55, 0.66, 0.5}},
        {{0, -15, 480}, {0.7, 0.5, 0.5}},  {{0, -15, 480}, {-0.7, 0.5, 0.5}},
        {{-10, 0, 470}, {0.35, 1, -0.25}},
    };
    return positions;
}

inline std::string ball_bar_triple(const Vec3& v) {
    std::ostringstream s;
    s.precision(17);
    s << "[" << v[0] << ", " << v[1] << ", " << v[2] << "]";
    return s.str();
}

// The scene of `p` (fpp-scene/1): wall, ball bar ("ball"), rod, stand.
inline std::string ball_bar_scene_yaml(const BallBarPlacement& p) {
    const Vec3 post{p.centre[0], p.centre[1] + 65, p.centre[2] + 5};
    std::ostringstream s;
    s.precision(17);
    s << "format: fpp-scene/1\nshapes:\n"
      << "  - {type: plane, name: wall, centre: [0, 0, 575], size: [420, 330], albedo: 0.8}\n"
      << "  - {type: ball_bar, name: ball, centre: " << ball_bar_triple(p.centre)
      << ", axis: " << ball_bar_triple(p.axis) << ", distance: " << p.length
      << ", radius: " << kBallDiameterMm / 2 << ", " << p.material << "}\n"
      << "  - {type: cylinder, name: rod, centre: " << ball_bar_triple(p.centre)
      << ", axis: " << ball_bar_triple(p.axis) << ", radius: 5, length: " << p.length - 28
      << ", albedo: 0.6}\n"
      << "  - {type: cylinder, name: stand, centre: " << ball_bar_triple(post)
      << ", axis: [0, 1, 0], radius: 8, length: 120, albedo: 0.7}\n";
    return s.str();
}

// The certificate of the bar: 150.000 mm, two 30.000 mm spheres.
inline const char* ball_bar_artefact_yaml() {
    return "format: fpp-artefact/1\n"
           "kind: ball-bar\n"
           "name: virtual ball bar\n"
           "sphere_diameters_mm: [30.000, 30.000]\n"
           "centre_distance_mm: 150.000\n"
           "uncertainty_mm: 0.001\n";
}

} // namespace fpp::test
