#include "fpp/scanner/api_events.hpp"

#include "api_json.hpp"

namespace fpp::scanner {

using nlohmann::json;

void ApiEvents::state_changed(const StateNow& state) {
    hub_.publish("state", api_json::state_event(state).dump());
}

void ApiEvents::table_changed(const std::optional<TableDescription>& table) {
    hub_.publish("table", api_json::table_event(table).dump());
}

void ApiEvents::scan_started(const ScanStart& scan) {
    hub_.publish("scan-started", api_json::scan_started_event(scan).dump());
}

void ApiEvents::frame_captured(const std::string& id, int frame, int frames) {
    hub_.publish("frame-captured", json{{"id", id}, {"frame", frame}, {"frames", frames}}.dump());
}

void ApiEvents::decoded(const std::string& id) {
    hub_.publish("decoded", json{{"id", id}}.dump());
}

void ApiEvents::scan_ended(const ScanEnd& scan) {
    hub_.publish(api_json::scan_ended_name(scan), api_json::scan_ended_event(scan).dump());
}

void ApiEvents::settings_changed(const ScannerSettings& settings) {
    hub_.publish("settings", json{{"exposure_us", settings.exposure_us}}.dump());
}

std::string ApiEvents::state_event(const StateNow& state) {
    return EventHub::format("state", api_json::state_event(state).dump());
}

} // namespace fpp::scanner
