// The service's events as the API's server-sent events
// (fpp/scanner/api_events.hpp, http-api.md "Events"): each event's name and
// its one line of JSON, as a stream of the hub receives them.

#include "fpp/scanner/api_events.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <optional>
#include <string>

using namespace fpp;
using namespace fpp::scanner;
using namespace std::chrono_literals;

namespace {

struct Stream {
    EventHub hub;
    std::shared_ptr<EventHub::Subscription> events = hub.subscribe("");
    ApiEvents api{hub};
    // The next event's text, "" when there is none.
    std::string next() { return events->next(0ms).value_or("closed"); }
};

TEST(ApiEvents, StateWithItsErrorOrNull) {
    Stream s;
    s.api.state_changed({ScannerState::idle, ""});
    s.api.state_changed({ScannerState::scanning, ""});
    s.api.state_changed({ScannerState::error, "gpiochip0 line 17: the chip went away"});
    EXPECT_EQ(s.next(), "event: state\ndata: {\"error\":null,\"state\":\"idle\"}\n\n");
    EXPECT_EQ(s.next(), "event: state\ndata: {\"error\":null,\"state\":\"scanning\"}\n\n");
    EXPECT_EQ(s.next(), "event: state\ndata: {\"error\":\"gpiochip0 line 17: the chip went "
                        "away\",\"state\":\"error\"}\n\n");
    EXPECT_EQ(s.next(), "");
    // A new stream's first event is the same text.
    EXPECT_EQ(ApiEvents::state_event({ScannerState::idle, ""}),
              "event: state\ndata: {\"error\":null,\"state\":\"idle\"}\n\n");
}

TEST(ApiEvents, TableWithItsModelAndFileHashOrNull) {
    Stream s;
    TableDescription table;
    table.path = "/var/lib/fpp-scanner/table.fpt";
    table.info.model = TableModel::rational;
    table.file_hash = 0x00c0ffee12345678ull;
    table.bytes = 4096;
    s.api.table_changed(table);
    s.api.table_changed(std::nullopt);
    EXPECT_EQ(s.next(), "event: table\ndata: "
                        "{\"file_fnv1a64\":\"00c0ffee12345678\",\"model\":\"rational\"}\n\n");
    EXPECT_EQ(s.next(), "event: table\ndata: null\n\n");
}

TEST(ApiEvents, AScanFromStartToEnd) {
    Stream s;
    s.api.scan_started({"scan-20240102-030405-006", ScanMode::scan, 28, "button", ""});
    s.api.frame_captured("scan-20240102-030405-006", 1, 28);
    s.api.decoded("scan-20240102-030405-006");
    ScanEnd end;
    end.id = "scan-20240102-030405-006";
    end.ok = true;
    end.points = 1234;
    end.quality.coverage = 0.875;
    s.api.scan_ended(end);
    EXPECT_EQ(s.next(), "event: scan-started\ndata: {\"frames\":28,\"id\":\"scan-20240102-030405-"
                        "006\",\"mode\":\"scan\",\"session\":null,\"source\":\"button\"}\n\n");
    EXPECT_EQ(s.next(), "event: frame-captured\ndata: {\"frame\":1,\"frames\":28,\"id\":\"scan-"
                        "20240102-030405-006\"}\n\n");
    EXPECT_EQ(s.next(), "event: decoded\ndata: {\"id\":\"scan-20240102-030405-006\"}\n\n");
    EXPECT_EQ(s.next(), "event: written\ndata: {\"id\":\"scan-20240102-030405-006\",\"mode\":"
                        "\"scan\",\"points\":1234,\"quality\":{\"advice\":\"\",\"coverage\":0.875,"
                        "\"good\":true,\"reasons\":[]},\"session\":null}\n\n");
    EXPECT_EQ(s.next(), "");
}

TEST(ApiEvents, ASessionsCaptureAndAPoorScan) {
    Stream s;
    s.api.scan_started({"pose-03", ScanMode::capture, 40, "api", "session-1"});
    ScanEnd end;
    end.id = "pose-03";
    end.mode = ScanMode::capture;
    end.ok = true;
    end.session = "session-1";
    end.quality.good = false;
    end.quality.coverage = 0.25;
    end.quality.reasons = {"30 % of the lit pixels saturated"};
    end.quality.advice = "lower the exposure";
    s.api.scan_ended(end);
    EXPECT_EQ(s.next(), "event: scan-started\ndata: {\"frames\":40,\"id\":\"pose-03\",\"mode\":"
                        "\"capture\",\"session\":\"session-1\",\"source\":\"api\"}\n\n");
    EXPECT_EQ(s.next(), "event: written\ndata: {\"id\":\"pose-03\",\"mode\":\"capture\",\"points\":"
                        "0,\"quality\":{\"advice\":\"lower the exposure\",\"coverage\":0.25,"
                        "\"good\":false,\"reasons\":[\"30 % of the lit pixels saturated\"]},"
                        "\"session\":\"session-1\"}\n\n");
}

TEST(ApiEvents, AFailedScanNamesItsError) {
    Stream s;
    ScanEnd end;
    end.id = "scan-2";
    end.ok = false;
    end.points = 99; // not reported for a failed scan
    end.error = "camera 10.0.0.7: no frame within 1000 ms";
    s.api.scan_ended(end);
    EXPECT_EQ(s.next(), "event: failed\ndata: {\"error\":\"camera 10.0.0.7: no frame within "
                        "1000 ms\",\"id\":\"scan-2\"}\n\n");
}

TEST(ApiEvents, SettingsAndTextThatNeedsEscaping) {
    Stream s;
    s.api.settings_changed(ScannerSettings{8000});
    s.api.settings_changed(ScannerSettings{12.5});
    s.api.state_changed({ScannerState::error, "line 1\nsaid \"no\""});
    EXPECT_EQ(s.next(), "event: settings\ndata: {\"exposure_us\":8000.0}\n\n");
    EXPECT_EQ(s.next(), "event: settings\ndata: {\"exposure_us\":12.5}\n\n");
    // One data line: the newline and quotes escaped in the JSON.
    EXPECT_EQ(
        s.next(),
        "event: state\ndata: {\"error\":\"line 1\\nsaid \\\"no\\\"\",\"state\":\"error\"}\n\n");
}

} // namespace
