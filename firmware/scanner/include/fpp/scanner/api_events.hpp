#pragma once
// The service's events as the API's server-sent events (http-api.md,
// "Events"): each rendered as JSON and published on the EventHub that the
// /api/v1/events streams follow.
#include <fpp/scanner/event_hub.hpp>
#include <fpp/scanner/service_reports.hpp>

#include <string>

namespace fpp::scanner {

class ApiEvents final : public ServiceEvents {
public:
    explicit ApiEvents(EventHub& hub) : hub_(hub) {}

    void state_changed(const StateNow& state) override;
    void table_changed(const std::optional<TableDescription>& table) override;
    void scan_started(const ScanStart& scan) override;
    void frame_captured(const std::string& id, int frame, int frames) override;
    void decoded(const std::string& id) override;
    void scan_ended(const ScanEnd& scan) override;
    void settings_changed(const ScannerSettings& settings) override;

    // The first event of a new stream: the state now, formatted.
    static std::string state_event(const StateNow& state);

private:
    EventHub& hub_;
};

} // namespace fpp::scanner
