#pragma once
// A camera-camera calibration: two cameras looking at the same scene, the
// projector between them only a texture (it needs no calibration). What
// two-camera scanning triangulates with.
//
// Conventions: the first camera's frame is the world frame, mm.
// X_2 = R X_1 + T. Both lenses use fpp::LensModel (pixel centres on integers,
// OpenCV's convention).

#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <filesystem>
#include <string>

namespace fpp::calib {

struct CameraPairCalibration {
    Size first_size;  // first camera, pixels ({0, 0} when the file does not say)
    Size second_size; // second camera
    LensModel first;
    LensModel second;
    Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1};
    Vec3 T{0, 0, 0};    // mm
    double rms = -1;    // stereo reprojection RMS, px (< 0 unknown)
    std::string origin; // where it was read from, and in which format

    double baseline() const; // |T|, mm: the distance between the optical centres
    // "two cameras of 1280 x 1024 and 1280 x 1024 px, baseline 120.3 mm".
    std::string summary() const;
};

// Files load_camera_pair reads (formats documented in
// firmware/core/formats/imports.md):
enum class CameraPairFormat {
    automatic,     // by content
    opencv_stereo, // OpenCV FileStorage, M1 D1 M2 D2 R T (stereo_calib sample; SLMaster's
                   // caliInfo.yml): X_2 = R X_1 + T
    bouguet,       // Bouguet's Camera Calibration Toolbox stereo results as text:
                   // fc_left cc_left alpha_c_left kc_left, ..._right, om, T: X_R = R(om) X_L + T
    matlab,        // MATLAB stereoParameters written as `name = mat2str(value)` lines:
                   // CameraParameters1.IntrinsicMatrix (transposed, 1-based), ...,
                   // RotationOfCamera2 (transposed), TranslationOfCamera2 (x2 = x1 R + t)
};

// "auto", "opencv-stereo", "bouguet", "matlab"; std::invalid_argument otherwise.
CameraPairFormat parse_camera_pair_format(const std::string& name);
const char* to_string(CameraPairFormat format);

// Reads a camera-camera calibration. Throws InputError naming the file and
// the key (or the line of a text format) for anything missing or malformed.
CameraPairCalibration load_camera_pair(const std::filesystem::path& path,
                                       CameraPairFormat format = CameraPairFormat::automatic);
// OpenCV's stereo_calib sample writes two files: intrinsics (M1 D1 M2 D2)
// and extrinsics (R T; R1 R2 P1 P2 Q ignored).
CameraPairCalibration load_camera_pair(const std::filesystem::path& intrinsics,
                                       const std::filesystem::path& extrinsics);
// Same from the file's text (`origin` named in errors).
CameraPairCalibration parse_camera_pair(const std::string& text,
                                        const std::filesystem::path& origin,
                                        CameraPairFormat format = CameraPairFormat::automatic);
// Whether a file's text looks like a camera-camera calibration of one of
// these formats (without validating it).
bool looks_like_camera_pair(const std::string& text);

} // namespace fpp::calib
