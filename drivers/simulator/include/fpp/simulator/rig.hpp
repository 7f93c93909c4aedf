#pragma once
// The virtual scanner's rig: camera and projector geometry (calibrated model
// plus effects a stereo calibration cannot capture) and radiometry.
//
// Frames: the camera frame is the world frame, mm. The projector frame is
// reached by X_p = R X_c + t. Euler angles in YAML are degrees with
// R = Rz(c) Ry(b) Rx(a) (see fpp/lens_model.hpp).

#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <cstdint>
#include <filesystem>
#include <string>

namespace fpp::sim {

struct SensorModel {
    int bit_depth = 8; // 8, 10, 12 or 16 significant bits; >8 written MSB-aligned in 16-bit PNG
    double white_level = 200.0; // DN (at bit_depth) for albedo 1 facing the projector at reference
                                // distance, pattern full on
    double ambient = 0.0;       // DN of ambient light on albedo 1 (also in projector shadows)
    double read_noise_dn = 0.0; // Gaussian sigma, DN
    double gain_e_per_dn = 0.0; // shot noise: electrons per DN; 0 = off
    double defocus_sigma_px = 0.0;      // camera blur, Gaussian sigma in camera pixels
    double reference_distance_mm = 0.0; // inverse-square falloff from the projector; 0 = off
};

struct ProjectorOptics {
    double gamma = 1.0;            // emitted = (level/255)^gamma
    double black_level = 0.0;      // fraction of full light emitted by level 0
    double defocus_sigma_px = 0.0; // Gaussian sigma in projector pixels
};

struct Rig {
    std::string name;
    Size camera_size;
    Size projector_size;
    LensModel camera;
    LensModel projector;
    Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1}; // X_p = R X_c + t
    Vec3 t{0, 0, 0};                   // mm
    SensorModel sensor;
    ProjectorOptics projector_optics;

    // The paper's Table 1 with every effect off (ideal 8-bit camera).
    static Rig paper();
    Vec3 projector_centre_in_camera() const; // -R^T t
    // Same geometry, all effects outside the stereo model off, no noise.
    Rig without_effects() const;
    // The camera with `factor` x `factor` pixel binning (smaller images with
    // the same field of view and distortion; fast tests). Pixel centres on
    // integers: c' = (c + 0.5) / factor - 0.5.
    Rig binned_camera(int factor) const;
    // Full-scale DN at the sensor's bit depth (2^bit_depth - 1).
    double full_scale_dn() const;
    // Throws InputError(origin, field, ...) if a value is out of range.
    void validate(const std::filesystem::path& origin = "rig") const;
};

// YAML rig files under board/sim/ (schema: the comment at the top of
// board/sim/paper-rig.yaml). Throws InputError naming file and field.
Rig load_rig(const std::filesystem::path& path);
std::string rig_to_yaml(const Rig& rig);
// board/sim/paper-rig.yaml in the source tree.
std::filesystem::path default_rig_path();
// board/sim/paper-rig-effects.yaml in the source tree.
std::filesystem::path effects_rig_path();
// board/sim/paper-rig-lens-defects.yaml in the source tree.
std::filesystem::path lens_defects_rig_path();
// board/sim/rig-prism-projector.yaml: thin-prism projector lens, short baseline.
std::filesystem::path prism_projector_rig_path();
// board/sim/rig-camera-defect.yaml: the camera lens has the defect.
std::filesystem::path camera_defect_rig_path();
// board/sim/rig-decentred-projector.yaml: decentred projector element, projector above.
std::filesystem::path decentred_projector_rig_path();

} // namespace fpp::sim
