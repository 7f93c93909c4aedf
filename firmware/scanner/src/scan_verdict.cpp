#include "fpp/scanner/scan_verdict.hpp"

#include "fpp/scanner/scan_store.hpp"
#include "fpp/yaml_fields.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>

namespace fpp::scanner {

namespace {

std::string percent(double fraction) {
    char text[32];
    std::snprintf(text, sizeof text, fraction < 0.1 ? "%.1f %%" : "%.0f %%", 100 * fraction);
    return text;
}

std::string exposure_text(double us) {
    char text[32];
    if (us >= 1000)
        std::snprintf(text, sizeof text, "%.3g ms", us / 1000);
    else
        std::snprintf(text, sizeof text, "%.3g us", us);
    return text;
}

} // namespace

ScanVerdict judge_scan(const ScanEvidence& e) {
    const DecodeStatistics& d = e.decode;
    ScanVerdict v;
    if (d.pixels == 0)
        return v;
    v.coverage = double(d.decoded) / double(d.pixels);
    const double lit = double(d.lit) / double(d.pixels);
    const double saturated = d.lit > 0 ? double(d.saturated) / double(d.lit) : 0.0;
    const double flat = d.lit > 0 ? double(d.low_modulation) / double(d.lit) : 0.0;
    const std::string now = " (now " + exposure_text(e.exposure_us) + ")";
    if (saturated >= 0.2) {
        v.reasons.push_back(percent(saturated) + " of the lit pixels are saturated");
        v.advice = "Lower the exposure" + now + ".";
    }
    if (lit < 0.02) {
        v.reasons.push_back("only " + percent(lit) + " of the camera's pixels see the fringes");
        v.advice = "Raise the exposure" + now + ", and check that the projector lights the part.";
    } else if (flat >= 0.5) {
        v.reasons.push_back(percent(flat) + " of the lit pixels show too little fringe contrast");
        v.advice = "Raise the exposure" + now + ".";
    }
    if (e.expects_points && e.points == 0)
        v.reasons.push_back("no point was made");
    if (e.last_good && v.coverage < 0.5 * e.last_good->coverage) {
        v.reasons.push_back(percent(v.coverage) + " of the camera decoded, against " +
                            percent(e.last_good->coverage) + " in the last good scan (" +
                            e.last_good->id + ")");
        if (v.advice.empty())
            v.advice = "Check that the part is in the field of view and in focus.";
    }
    if (!v.reasons.empty() && v.advice.empty())
        v.advice = "Check the part's place and the exposure" + now + ".";
    v.good = v.reasons.empty();
    return v;
}

std::optional<GoodScan> newest_good_scan(const std::filesystem::path& store,
                                         const std::filesystem::path& except, int look_back) {
    const std::vector<std::filesystem::path> scans = list_scans(store);
    for (auto it = scans.rbegin(); it != scans.rend() && look_back > 0; ++it, --look_back) {
        if (*it == except)
            continue;
        try {
            const auto meta = nlohmann::json::parse(yaml_fields::read_text_file(*it / "scan.json"));
            const auto& q = meta.at("quality");
            if (q.at("good").get<bool>())
                return GoodScan{it->filename().string(), q.at("coverage").get<double>()};
        } catch (const std::exception&) {
            // No scan.json, or one from before `quality`: not a comparison.
        }
    }
    return std::nullopt;
}

} // namespace fpp::scanner
