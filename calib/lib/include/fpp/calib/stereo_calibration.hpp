#pragma once
// A camera-projector pair calibrated as a stereo pair ("projector as an
// inverse camera"), and its file format.
//
// Conventions: camera frame = world frame, mm. X_p = R X_c + T. Both lenses use
// fpp::LensModel (pinhole with skew in K(0,1), Brown-Conrady k1 k2 k3 p1 p2;
// pixel centres on integers).
//
// File: OpenCV FileStorage YAML ("fpp-stereo/1"; keys camera_size,
// camera_matrix, camera_distortion, the projector's alike, R, T, RMS, poses,
// optional correction grids), readable by OpenCV directly. Also read:
// SLStudio's calibration.xml, SLMaster's caliInfo.yml and, named explicitly,
// camera-camera files (CalibrationFormat).
// Format: firmware/core/formats/calibration-file.md (other tools' files:
// firmware/core/formats/imports.md)

#include "fpp/calib/camera_pair.hpp"
#include "fpp/calib/correction_grid.hpp"
#include "fpp/calib/trueness.hpp"
#include "fpp/error.hpp"
#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace fpp::calib {

inline constexpr const char* kStereoFormat = "fpp-stereo/1";

// Formats readable by load_calibration.
enum class CalibrationFormat {
    automatic, // by content: ours, SLStudio's calibration.xml, SLMaster's caliInfo.yml
    fpp,       // ours (keys above)
    slstudio,  // Kc kc Kp kp Rp Tp, frameWidth/Height, screenResX/Y (X_p = Rp X_c + Tp)
    slmaster,  // M1 D1 M4 D4 Rlp Tlp (X_p = Rlp X_c + Tlp); sizes must be given
    // Two-device formats (camera_pair.hpp), read as camera (first device) and
    // projector (second) only when named explicitly; found by content they
    // are camera-camera calibrations (CameraPairFileError). Sizes unknown.
    opencv_stereo, // M1 D1 M2 D2 R T
    bouguet,       // Bouguet's stereo results text
    matlab,        // MATLAB stereoParameters text
};

// load_calibration / parse_calibration found a camera-camera calibration
// (two cameras; the projector, if any, only a texture): it allows two-camera
// scanning (fpp-calib reconstruct with two capture sets), not a
// camera-projector table. The pair is read in full.
class CameraPairFileError : public InputError {
public:
    CameraPairFileError(const std::filesystem::path& file, CameraPairCalibration pair_);
    CameraPairCalibration pair;
};

struct PoseResidual {
    std::string name;         // capture folder name
    double camera_rms = 0;    // px
    double projector_rms = 0; // px
    int corners = 0;
    bool used = true; // false if dropped as an outlier
    std::string note; // why it was dropped or skipped
};

// An in-field correction of the depth scale with a certified artefact
// (`fpp-calib correct`): the camera's focal lengths scaled by focal_scale
// before the session was calibrated again; what the artefact's lengths
// showed of the depth scale k before (round 0) and after (the last round),
// as (k - 1) in ppm with one sigma.
struct DepthCorrection {
    double focal_scale = 1;
    double before_ppm = 0, before_sigma_ppm = 0;
    double after_ppm = 0, after_sigma_ppm = 0;
    int positions = 0;    // artefact positions the fit used
    std::string artefact; // its certificate's name, or file
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
    double camera_rms = -1;       // px, < 0 if unknown
    double projector_rms = -1;    // px, < 0 if unknown
    std::vector<PoseResidual> poses;
    // What the calibration's uncertainty means for lengths (trueness.hpp);
    // unknown for a calibration read without it or made elsewhere.
    Trueness trueness;
    std::optional<DepthCorrection> depth_correction;   // none: never corrected
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

// "auto", "fpp", "slstudio", "slmaster", "opencv-stereo", "bouguet", "matlab"; throws
// std::invalid_argument otherwise.
CalibrationFormat parse_calibration_format(const std::string& name);
const char* to_string(CalibrationFormat format);

// A camera-camera file found by content (automatic format) throws
// CameraPairFileError, which says what the file is and what it allows.
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
