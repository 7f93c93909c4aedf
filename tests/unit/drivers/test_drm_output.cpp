// Choosing the DRM output (fpp/drivers/drm_output.hpp): the connector and the
// mode a board file asks for, from what the card reports, without a device;
// refusals list what there is.

#include "test_support.hpp"

#include <gtest/gtest.h>

#if __has_include(<fpp/drivers/drm_output.hpp>)

#include "fpp/drivers/device_error.hpp"
#include "fpp/drivers/drm_output.hpp"
#include "fpp/error.hpp"

#include <string>
#include <vector>

namespace {

using fpp::drivers::choose_drm_output;
using fpp::drivers::DeviceError;
using fpp::drivers::DrmConnectorInfo;
using fpp::drivers::DrmOutputRequest;

// A board with a disconnected HDMI port, a projector on the second HDMI port
// and a DSI panel.
std::vector<DrmConnectorInfo> board() {
    return {
        {"HDMI-A-1", false, {}},
        {"HDMI-A-2",
         true,
         {{1920, 1080, 60.0, false},
          {1280, 800, 59.91, false},
          {1280, 800, 119.9, false},
          {1280, 800, 60.0, true},
          {640, 480, 59.94, false}}},
        {"DSI-1", true, {{800, 480, 60.0, true}}},
    };
}

std::string message_of(const std::vector<DrmConnectorInfo>& connectors,
                       const DrmOutputRequest& request) {
    try {
        (void)choose_drm_output(connectors, request, "display card0");
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.device(), "display card0");
        EXPECT_EQ(e.kind(), fpp::drivers::DeviceKind::display);
        return e.what();
    }
    ADD_FAILURE() << "no error for connector '" << request.connector << "' mode '" << request.mode
                  << "'";
    return "";
}

TEST(DrmOutput, DefaultsToFirstConnectedConnectorAndItsPreferredMode) {
    const auto choice = choose_drm_output(board(), {});
    EXPECT_EQ(choice.connector, 1u);
    EXPECT_EQ(choice.mode, 3u); // 1280x800@60, flagged preferred, listed after others
}

TEST(DrmOutput, WithoutAPreferredModeTakesTheFirst) {
    auto connectors = board();
    connectors[1].modes[3].preferred = false;
    EXPECT_EQ(choose_drm_output(connectors, {}).mode, 0u);
}

TEST(DrmOutput, NamedConnectorAndSize) {
    EXPECT_EQ(choose_drm_output(board(), {"DSI-1", ""}).connector, 2u);
    // Same size: the preferred one wins over a higher refresh.
    EXPECT_EQ(choose_drm_output(board(), {"HDMI-A-2", "1280x800"}).mode, 3u);
    // Without a preferred one of that size: the highest refresh.
    auto connectors = board();
    connectors[1].modes[3].preferred = false;
    EXPECT_EQ(choose_drm_output(connectors, {"HDMI-A-2", "1280x800"}).mode, 2u);
    // A refresh picks within 0.5 Hz.
    EXPECT_EQ(choose_drm_output(board(), {"", "1280x800@120"}).mode, 2u);
    EXPECT_EQ(choose_drm_output(board(), {"", "1280x800@59.9"}).mode, 1u);
    EXPECT_EQ(choose_drm_output(board(), {"", "640x480"}).mode, 4u);
}

TEST(DrmOutput, NothingFittingIsADeviceErrorListingWhatThereIs) {
    std::string what = message_of(board(), {"HDMI-A-1", ""});
    EXPECT_NE(what.find("connector HDMI-A-1 is not present and connected"), std::string::npos)
        << what;
    EXPECT_NE(what.find("HDMI-A-1 (disconnected), HDMI-A-2, DSI-1"), std::string::npos) << what;
    what = message_of(board(), {"VGA-1", ""});
    EXPECT_NE(what.find("VGA-1"), std::string::npos) << what;
    what = message_of(board(), {"", "1024x768"});
    EXPECT_NE(what.find("has no mode 1024x768"), std::string::npos) << what;
    EXPECT_NE(what.find("1280x800@60.00*"), std::string::npos) << what;
    what = message_of(board(), {"", "1280x800@75"});
    EXPECT_NE(what.find("has no mode 1280x800@75"), std::string::npos) << what;
    what = message_of({{"HDMI-A-1", false, {}}}, {});
    EXPECT_NE(what.find("no connected connector"), std::string::npos) << what;
    what = message_of({}, {});
    EXPECT_NE(what.find("(connectors: none)"), std::string::npos) << what;
}

TEST(DrmOutput, ParsesModes) {
    const auto spec = fpp::drivers::parse_drm_mode("1280x800@59.94");
    EXPECT_EQ(spec.width, 1280);
    EXPECT_EQ(spec.height, 800);
    EXPECT_DOUBLE_EQ(spec.refresh_hz, 59.94);
    EXPECT_EQ(fpp::drivers::parse_drm_mode("640x480").refresh_hz, 0.0);
    for (const char* bad : {"", "1280", "1280x", "x800", "1280x800@", "1280x800@0", "-1x800",
                            "1280X800", "1280x800@60Hz", "99999999x1"}) {
        try {
            (void)fpp::drivers::parse_drm_mode(bad);
            ADD_FAILURE() << "accepted '" << bad << "'";
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.field(), "mode") << bad;
        }
    }
}

} // namespace

#else

TEST(DrmOutput, NotBuilt) {
    if (fpp::test::in_ci())
        FAIL() << "fpp_drm is not linked to this test";
    GTEST_SKIP() << "the DRM display driver is not built (libdrm not found)";
}

#endif
