#include "scan_metadata.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <ctime>

namespace fpp::scanner {

std::string hex64(std::uint64_t v) {
    char buf[24];
    std::snprintf(buf, sizeof buf, "%016" PRIx64, v);
    return buf;
}

nlohmann::json trueness_json(const TableTrueness& t) {
    if (!t.known())
        return nullptr;
    // Rounded to what the figures mean (0.1 um, 1 ppm).
    const auto um = [](float mm) { return std::round(double(mm) * 1e4) / 1e4; };
    const auto ppm = [&](float sigma) {
        return std::round(double(sigma) / double(t.length_mm) * 1e6);
    };
    return {{"length_mm", um(t.length_mm)},
            {"depth_mm", um(t.depth_mm)},
            {"sigma_along_depth_mm", um(t.along_depth_mm)},
            {"sigma_across_mm", um(t.across_mm)},
            {"along_depth_ppm", ppm(t.along_depth_mm)},
            {"across_ppm", ppm(t.across_mm)}};
}

std::string utc_text(std::int64_t unix_s) {
    const auto t = static_cast<std::time_t>(unix_s);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buf;
}

std::optional<std::string> file_written_utc(const std::filesystem::path& path) {
    std::error_code ec;
    const auto written = std::filesystem::last_write_time(path, ec);
    if (ec)
        return std::nullopt;
    return utc_text(std::chrono::duration_cast<std::chrono::seconds>(
                        std::chrono::file_clock::to_sys(written).time_since_epoch())
                        .count());
}

nlohmann::json quality_json(const ScanVerdict& v) {
    return {
        {"good", v.good}, {"coverage", v.coverage}, {"reasons", v.reasons}, {"advice", v.advice}};
}

std::string scan_json(const ScanMetadata& m) {
    const auto& s = m.board.camera.settings;
    const ScanTimings& t = m.outcome.timings;
    nlohmann::ordered_json flips = nlohmann::ordered_json::array();
    for (const FrameRecord& r : m.records)
        flips.push_back({{"pattern", r.flip.index},
                         {"sequence", r.flip.sequence},
                         {"flip_ns", r.flip.timestamp_ns},
                         {"frame_id", r.frame_id},
                         {"frame_ns", r.frame_timestamp_ns}});
    // Keys in the order a person reads them (ordered_json keeps insertion).
    nlohmann::ordered_json j;
    j["format"] = "fpp-scan/1";
    j["board"] = m.board.name;
    j["mode"] = name_of(kScanModeNames, m.mode, "capture");
    j["started_utc"] = m.started_utc;
    j["camera"] = {{"width", m.camera.width},
                   {"height", m.camera.height},
                   {"bit_depth", m.camera_bit_depth},
                   {"pixel_format", s.pixel_format},
                   {"exposure_us", m.settings.exposure_us},
                   {"trigger", name_of(drivers::kTriggerModeNames, s.trigger, "software")}};
    j["projector"] = {{"width", m.projector.width}, {"height", m.projector.height}};
    j["sequence"] = m.board.sequence_name.empty() ? "blocks" : m.board.sequence_name;
    j["frames"] = m.outcome.frames;
    j["timing_settings_us"] = {{"settle", m.board.timing.settle.count()},
                               {"trigger_pulse", m.board.timing.trigger_pulse.count()}};
    if (m.table)
        j["table"] = {{"path", m.table->path.string()},
                      {"model", to_string(m.table->model)},
                      {"file_fnv1a64", hex64(m.table->file_hash)},
                      {"calibration_fnv1a64", hex64(m.table->calibration_hash)},
                      {"trueness", trueness_json(m.table->trueness)}};
    if (m.board.projector_response)
        j["projector_response"] = m.board.projector_response->string();
    const DecodeStatistics& d = m.decode_statistics;
    j["decode"] = {{"method_x", m.method_x},
                   {"method_y", m.method_y},
                   {"statistics_of", m.decode_statistics_of},
                   {"pixels", d.pixels},
                   {"lit_floor_dn", d.lit_floor},
                   {"lit_floor_rule", d.floor_from_dark_mode ? "dark_mode" : "full_scale_fraction"},
                   {"lit", d.lit},
                   {"decoded", d.decoded},
                   {"coverage_of_lit", d.coverage_of_lit()},
                   {"dropped",
                    {{"dark", d.dark},
                     {"saturated", d.saturated},
                     {"low_modulation", d.low_modulation},
                     {"unwrap_inconsistent", d.unwrap_inconsistent},
                     {"out_of_range", d.out_of_range},
                     {"no_cue", d.no_cue},
                     {"other", d.other}}}};
    j["exposures_us"] = m.outcome.exposures_us;
    if (m.outcome.fusion) {
        const FusionStats& f = *m.outcome.fusion;
        j["fusion"] = {{"reference_pixels", f.reference_pixels},
                       {"averaged", f.averaged},
                       {"disagreeing", f.disagreeing},
                       {"undecoded", f.undecoded}};
    }
    j["points"] = m.outcome.points;
    j["quality"] = quality_json(m.outcome.verdict);
    j["sigma_z"] = m.outcome.has_sigma;
    if (m.board.points.max_sigma_z_mm)
        j["dropped_by_sigma"] = {{"max_sigma_z_mm", *m.board.points.max_sigma_z_mm},
                                 {"points", m.outcome.dropped_by_sigma}};
    j["timings_ms"] = {{"capture", t.capture_ms},   {"push_mean", t.push_mean_ms},
                       {"push_max", t.push_max_ms}, {"finish", t.finish_ms},
                       {"fuse", t.fuse_ms},         {"apply", t.apply_ms}};
    j["flips"] = std::move(flips);
    return j.dump(2) + "\n";
}

} // namespace fpp::scanner
