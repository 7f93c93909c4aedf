// The DRM/KMS display's failure without a card. (The flips themselves need a
// KMS device: the virtual board; the choice of output is test_drm_output.cpp.)

#include "test_support.hpp"

#include <gtest/gtest.h>

#if __has_include(<fpp/drivers/drm_display.hpp>)

#include "fpp/drivers/device_error.hpp"
#include "fpp/drivers/drm_display.hpp"

#include <string>

namespace {

using fpp::drivers::DeviceError;

TEST(DrmDisplay, MissingCardIsADeviceErrorNamingThePath) {
    fpp::test::TempDir dir;
    const std::string path = (dir / "card7").string();
    fpp::drivers::DrmDisplaySettings settings;
    settings.card = path;
    try {
        fpp::drivers::DrmDisplay display(settings);
        FAIL() << "opened " << path;
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.device(), "display " + path);
        EXPECT_NE(std::string(e.what()).find("cannot open: No such file or directory"),
                  std::string::npos)
            << e.what();
    }
}

TEST(DrmDisplay, AFileThatIsNoKmsDeviceIsADeviceError) {
    fpp::drivers::DrmDisplaySettings settings;
    settings.card = "/dev/null";
    try {
        fpp::drivers::DrmDisplay display(settings);
        FAIL() << "/dev/null taken for a KMS card";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.device(), "display /dev/null");
        EXPECT_NE(std::string(e.what()).find("not a KMS device"), std::string::npos) << e.what();
    }
}

} // namespace

#else

TEST(DrmDisplay, NotBuilt) {
    if (fpp::test::in_ci())
        FAIL() << "fpp_drm is not linked to this test";
    GTEST_SKIP() << "the DRM display driver is not built (libdrm not found)";
}

#endif
