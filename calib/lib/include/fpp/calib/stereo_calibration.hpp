#pragma once
// A camera-projector pair calibrated as a stereo pair ("projector as an
// inverse camera"), and its file format.
//
// Conventions: camera frame = world frame, mm. X_p = R X_c + T. Both lenses use
// fpp::LensModel (pinhole with skew in K(0,1), Brown-Conrady k1 k2 k3 p1 p2;
// pixel centres on integers).
//
// File: OpenCV FileStorage YAML with the keys
//   format                             "fpp-stereo/1" (optional when reading)
//   camera_size, projector_size        [width, height]
//   camera_matrix, projector_matrix    3x3, skew in (0,1)
//   camera_distortion, projector_distortion   1x5: k1 k2 p1 p2 k3 (OpenCV order)
//   R (3x3), T (3x1, mm)               X_p = R X_c + T
//   camera_rms, projector_rms          reprojection RMS, px (-1 = unknown)
//   camera_correction_du, camera_correction_dv       optional (both or neither):
//   projector_correction_du, projector_correction_dv  a dense correction of
//                                      the lens model (correction_grid.hpp):
//                                      rows x columns control points, px, over
//                                      the device's image
//   board_square_size                  optional: mm, the square size of the
//                                      checkerboard session calibrated from
//   poses                              per-pose names, RMS and whether used:
//                                      a list of maps {name, camera_rms,
//                                      projector_rms, corners, used, note}
//   origin                             free text (optional)
// Matrices are !!opencv-matrix nodes of doubles, so that OpenCV (C++ and
// Python) reads them with FileStorage directly. Reading accepts any element
// type, 5x1 as well as 1x5 distortion and 4 coefficients (k3 = 0); 8, 12 or
// 14 coefficients only if those beyond k3 are zero (the rational and prism
// terms are not part of the model).
//
// Foreign formats (CalibrationFormat):
//   SLStudio calibration.xml: Kc, kc, Kp, kp, Rp, Tp (X_p = Rp X_c + Tp, mm),
//     frameWidth, frameHeight, screenResX, screenResY; cam_error and
//     proj_error become camera_rms and projector_rms.
//   SLMaster caliInfo.yml: M1, D1 (camera), M4, D4 (projector), Rlp, Tlp
//     (X_p = Rlp X_c + Tlp, mm). It records no projector size and no camera
//     size we can rely on: both are left {0, 0} (sizes_known() false) and the
//     user supplies them (fpp-calib reconstruct takes them from the capture).
// All three use OpenCV's pixel convention (centres on integers), as we do.

#include "fpp/calib/correction_grid.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace fpp::sim {
struct Rig;
}

namespace fpp::calib {

inline constexpr const char* kStereoFormat = "fpp-stereo/1";

// Formats readable by load_calibration.
enum class CalibrationFormat {
    automatic, // by content: ours, SLStudio's calibration.xml, SLMaster's caliInfo.yml
    fpp,       // ours (keys above)
    slstudio,  // Kc kc Kp kp Rp Tp, frameWidth/Height, screenResX/Y (X_p = Rp X_c + Tp)
    slmaster,  // M1 D1 M4 D4 Rlp Tlp (X_p = Rlp X_c + Tlp); sizes must be given
};

struct PoseResidual {
    std::string name;         // capture folder name
    double camera_rms = 0;    // px
    double projector_rms = 0; // px
    int corners = 0;
    bool used = true; // false if dropped as an outlier
    std::string note; // why it was dropped or skipped
};

struct StereoCalibration {
    Size camera_size;
    Size projector_size;
    LensModel camera;
    LensModel projector;
    // Dense corrections of the lens models (empty: none).
    CorrectionGrid camera_correction;
    CorrectionGrid projector_correction;
    Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Vec3 T{0, 0, 0};
    double board_square_size = 0; // mm; 0 = unknown
    double camera_rms = -1;    // px, < 0 if unknown
    double projector_rms = -1; // px, < 0 if unknown
    std::vector<PoseResidual> poses;
    std::string origin;                                // where it was read from or how it was made
    CalibrationFormat format = CalibrationFormat::fpp; // the format it was read from

    Vec3 projector_centre() const; // in the camera frame, mm: -R^T T
    // Through the whole model (lens, then correction): a camera-frame point
    // (mm, Z > 0) to its camera pixel, and to its projector pixel.
    Vec2 camera_pixel(const Vec3& camera_point) const;
    Vec2 projector_pixel(const Vec3& camera_point) const;
    // A camera pixel's undistorted ray (xn, yn, 1); false where the model
    // cannot be inverted.
    bool camera_ray(Vec2 pixel, Vec2& normalised) const;
    // Both sizes set (foreign formats may lack them).
    bool sizes_known() const;
};

// The exact stereo model of a simulated rig (its lenses, R and t; sizes from
// the rig). With rig.without_effects() the simulator renders exactly this
// model. Pose list empty, RMS unknown.
StereoCalibration calibration_from_rig(const sim::Rig& rig);

// "auto", "fpp", "slstudio", "slmaster"; throws std::invalid_argument otherwise.
CalibrationFormat parse_calibration_format(const std::string& name);
const char* to_string(CalibrationFormat format);

// Throws InputError naming the file and the missing or malformed key (a file
// that cannot be opened or parsed: the file and an empty key). Checks: every
// key present, matrices of the right shape with finite values, camera
// matrices upper triangular with positive focal lengths and K(2,2) = 1, R a
// rotation (orthonormal to 1e-5, det +1), sizes positive integers.
StereoCalibration load_calibration(const std::filesystem::path& path,
                                   CalibrationFormat format = CalibrationFormat::automatic);
// Same, from the file's text (`origin` is named in errors and kept in
// StereoCalibration::origin).
StereoCalibration parse_calibration(const std::string& text, const std::filesystem::path& origin,
                                    CalibrationFormat format = CalibrationFormat::automatic);
// Our format as text (what save_calibration writes). Throws
// std::invalid_argument if the calibration cannot be represented: unknown
// sizes, non-finite values, or lens terms outside the 5-coefficient model
// (k4, s1..s4 non-zero).
std::string calibration_to_yaml(const StereoCalibration& calibration);
// Writes our format atomically (temporary file, fsync, rename). Throws as
// calibration_to_yaml, and IoError.
void save_calibration(const std::filesystem::path& path, const StereoCalibration& calibration);

} // namespace fpp::calib
