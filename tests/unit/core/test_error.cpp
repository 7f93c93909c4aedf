// The errors for bad input and for the operating system (fpp/error.hpp): the
// message names the file, then the field when there is one, then what is
// wrong; file and field are kept for callers that test them.

#include "fpp/error.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace {

TEST(Error, InputErrorNamesTheFileTheFieldAndWhatIsWrong) {
    const fpp::InputError e("/boards/rpi5.yaml", "camera.exposure_us", "must be in 10..1000000");
    EXPECT_STREQ(e.what(), "/boards/rpi5.yaml: camera.exposure_us: must be in 10..1000000");
    EXPECT_EQ(e.file(), "/boards/rpi5.yaml");
    EXPECT_EQ(e.field(), "camera.exposure_us");
}

TEST(Error, InputErrorWithoutAFieldNamesTheFileOnly) {
    const fpp::InputError e("capture/capture.yaml", "", "not found");
    EXPECT_STREQ(e.what(), "capture/capture.yaml: not found");
    EXPECT_EQ(e.field(), "");
    // Caught as what it is, or as any runtime error.
    try {
        throw e;
    } catch (const std::runtime_error& caught) {
        EXPECT_STREQ(caught.what(), "capture/capture.yaml: not found");
    }
}

TEST(Error, IoErrorNamesThePath) {
    const fpp::IoError e("/scans/scan-1/cloud.ply", "No space left on device");
    EXPECT_STREQ(e.what(), "/scans/scan-1/cloud.ply: No space left on device");
    const std::runtime_error& base = e;
    EXPECT_STREQ(base.what(), e.what());
}

} // namespace
