// A camera-camera calibration (imports): OpenCV's stereo_calib FileStorage
// (M1 D1 M2 D2 R T), Bouguet's toolbox text, MATLAB stereoParameters text;
// found by content and named, as a camera pair and as a projector-camera
// calibration read from those formats.
#include "fpp/calib/camera_pair.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using fpp::calib::CalibrationFormat;
    using fpp::calib::CameraPairFormat;
    const std::string text = fpp::fuzz::as_text(data, size);
    (void)fpp::calib::looks_like_camera_pair(text);
    for (const CameraPairFormat format :
         {CameraPairFormat::automatic, CameraPairFormat::opencv_stereo, CameraPairFormat::bouguet,
          CameraPairFormat::matlab}) {
        fpp::fuzz::expect_declared_errors(
            [&] { (void)fpp::calib::parse_camera_pair(text, "pair.txt", format); });
    }
    for (const CalibrationFormat format : {CalibrationFormat::opencv_stereo,
                                           CalibrationFormat::bouguet, CalibrationFormat::matlab}) {
        fpp::fuzz::expect_declared_errors(
            [&] { (void)fpp::calib::parse_calibration(text, "pair.txt", format); });
    }
    return 0;
}
