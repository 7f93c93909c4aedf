// A projector-camera calibration file: ours, SLStudio's calibration.xml and
// SLMaster's caliInfo.yml, found by content and named explicitly. Found by
// content, a camera-camera file is refused with CameraPairFileError (an
// InputError).
#include "fpp/calib/stereo_calibration.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using fpp::calib::CalibrationFormat;
    const std::string text = fpp::fuzz::as_text(data, size);
    for (const CalibrationFormat format :
         {CalibrationFormat::automatic, CalibrationFormat::fpp, CalibrationFormat::slstudio,
          CalibrationFormat::slmaster}) {
        fpp::fuzz::expect_declared_errors(
            [&] { (void)fpp::calib::parse_calibration(text, "calibration.yml", format); });
    }
    return 0;
}
