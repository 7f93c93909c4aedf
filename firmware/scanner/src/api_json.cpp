#include "api_json.hpp"

#include "scan_metadata.hpp"

namespace fpp::scanner::api_json {

using nlohmann::json;

namespace {

json size_json(Size s) {
    return {{"width", s.width}, {"height", s.height}};
}

json text_or_null(const std::string& s) {
    return s.empty() ? json(nullptr) : json(s);
}

const char* mode_name(ScanMode mode) {
    return name_of(kScanModeNames, mode, "capture");
}

json last_scan(const std::optional<ScanEnd>& s) {
    if (!s)
        return nullptr;
    json j = {{"id", s->id},
              {"mode", mode_name(s->mode)},
              {"ok", s->ok},
              {"points", s->points},
              {"error", s->ok ? json(nullptr) : json(s->error)},
              {"session", text_or_null(s->session)}};
    if (s->ok)
        j["quality"] = quality_json(s->quality);
    return j;
}

} // namespace

json table(const std::optional<TableDescription>& t) {
    if (!t)
        return nullptr;
    return {{"path", t->path.string()},
            {"model", to_string(t->info.model)},
            {"camera", size_json(t->info.camera)},
            {"projector", size_json(t->info.projector)},
            {"bytes", t->bytes},
            {"file_fnv1a64", hex64(t->file_hash)},
            {"calibration_fnv1a64", hex64(t->info.calibration_hash)},
            {"trueness", trueness_json(t->info.trueness)},
            {"created_utc", utc_text(t->info.created_unix_s)},
            {"installed_utc", t->installed_utc ? json(*t->installed_utc) : json(nullptr)}};
}

json status(const ScannerStatus& s) {
    return {
        {"api", 1},
        {"state", to_string(s.state.state)},
        {"error", text_or_null(s.state.error)},
        {"board",
         {{"name", s.board_name}, {"simulated", s.simulated}, {"session_board", s.session_board}}},
        {"camera",
         {{"width", s.camera.width},
          {"height", s.camera.height},
          {"bit_depth", s.camera_bit_depth},
          {"pixel_format", s.pixel_format},
          {"exposure_us", s.settings.exposure_us}}},
        {"display", size_json(s.display)},
        {"sequence", {{"name", s.sequence_name}, {"frames", s.sequence_frames}}},
        {"table", table(s.table)},
        {"store",
         {{"directory", s.store_directory.string()},
          {"used_bytes", s.store_used_bytes},
          {"max_bytes", s.store_max_bytes},
          {"scans", s.store_scans},
          {"sessions", s.store_sessions}}},
        {"last_scan", last_scan(s.last_scan)},
        {"scans_completed", s.scans_completed}};
}

json response(const ResponseRecorded& r) {
    return {{"levels", r.levels}, {"frames", r.frames}};
}

json state_event(const StateNow& s) {
    return {{"state", to_string(s.state)}, {"error", text_or_null(s.error)}};
}

json table_event(const std::optional<TableDescription>& t) {
    if (!t)
        return nullptr;
    return {{"model", to_string(t->info.model)}, {"file_fnv1a64", hex64(t->file_hash)}};
}

json scan_started_event(const ScanStart& s) {
    return {{"id", s.id},
            {"mode", mode_name(s.mode)},
            {"frames", s.frames},
            {"source", s.source},
            {"session", text_or_null(s.session)}};
}

json scan_ended_event(const ScanEnd& s) {
    if (!s.ok)
        return {{"id", s.id}, {"error", s.error}};
    return {{"id", s.id},
            {"mode", mode_name(s.mode)},
            {"points", s.points},
            {"quality", quality_json(s.quality)},
            {"session", text_or_null(s.session)}};
}

const char* scan_ended_name(const ScanEnd& s) {
    return s.ok ? "written" : "failed";
}

} // namespace fpp::scanner::api_json
