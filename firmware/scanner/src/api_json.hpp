#pragma once
// The service's reports as the API's JSON (firmware/scanner/http-api.md):
// the one place that knows the wire names.
#include "fpp/scanner/service_reports.hpp"

#include <nlohmann/json.hpp>

#include <optional>

namespace fpp::scanner::api_json {

nlohmann::json status(const ScannerStatus& status);
// null without a table.
nlohmann::json table(const std::optional<TableDescription>& table);
nlohmann::json response(const ResponseRecorded& recorded);

// Event data (the `data:` line of each event).
nlohmann::json state_event(const StateNow& state);
nlohmann::json table_event(const std::optional<TableDescription>& table);
nlohmann::json scan_started_event(const ScanStart& scan);
nlohmann::json scan_ended_event(const ScanEnd& scan); // `written` or `failed`
const char* scan_ended_name(const ScanEnd& scan);     // "written" or "failed"

} // namespace fpp::scanner::api_json
