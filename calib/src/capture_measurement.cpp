#include "capture_measurement.hpp"

#include "cli_util.hpp"
#include "decode_outputs.hpp"
#include "table_reconstruction.hpp"

#include "fpp/calib/plots.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/fnv1a.hpp"
#include "fpp/image_io.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

namespace fpp::calib {

namespace fs = std::filesystem;

std::string hash_text(std::uint64_t hash) {
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
    return text;
}

std::uint64_t file_hash(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    if (!in || in.bad())
        throw IoError(path, "cannot read");
    const std::string all = bytes.str();
    return fnv1a64(all.data(), all.size());
}

namespace {

// A capture the scanner made (scan-*/capture*) whose scan.json names
// another table than --table: its clouds were not this table's, and mixing
// the two is almost always a mistake (a scanner recalibrated since).
void check_scan_record(const fs::path& capture, const fs::path& table, std::uint64_t table_hash) {
    fs::path folder = capture.lexically_normal();
    if (folder.filename().empty())
        folder = folder.parent_path();
    if (folder.filename().string().rfind("capture", 0) != 0)
        return;
    const fs::path record = folder.parent_path() / "scan.json";
    std::ifstream in(record);
    if (!in)
        return;
    const nlohmann::json scan = nlohmann::json::parse(in, nullptr, false);
    if (!scan.is_object() || !scan.contains("table") || !scan["table"].is_object())
        return;
    const nlohmann::json& t = scan["table"];
    if (!t.contains("file_fnv1a64") || !t["file_fnv1a64"].is_string())
        return;
    const std::string recorded = t["file_fnv1a64"].get<std::string>();
    if (recorded != hash_text(table_hash))
        throw InputError(record, "table.file_fnv1a64",
                         "the scanner made " + folder.string() + " with another table (" +
                             t.value("path", std::string("?")) + ", FNV-1a " + recorded +
                             ") than --table " + table.string() + " (FNV-1a " +
                             hash_text(table_hash) +
                             "): a capture of another calibration (--any-table to verify this "
                             "table on it anyway)");
}

// The simulator's true points of a capture, or empty.
Image<float> capture_truth(const CaptureSet& capture) {
    if (!capture.manifest.truth || capture.manifest.truth->xyz.empty())
        return {};
    Image<float> truth = read_tiff_float(capture.folder / capture.manifest.truth->xyz);
    if (truth.channels() != 3 || truth.size() != capture.manifest.camera)
        return {};
    return truth;
}

} // namespace

std::optional<MeasuredPosition> measure_capture(const fs::path& path, const CaptureMeasurement& how,
                                                const Artefact& artefact,
                                                std::optional<CoefficientTable>& table,
                                                const VerificationOptions& options) {
    const CaptureSet capture = read_capture_set(path);
    check_capture_axes(capture, ReconstructAxes::x);
    if (!table)
        table = load_table_for_capture(how.table_path, capture);
    else
        check_table_fits_capture(*table, how.table_path, capture);
    if (how.table_hash != 0)
        check_scan_record(path, how.table_path, how.table_hash);
    CoordinateFilterOptions no_smoothing;
    no_smoothing.radius = 0;
    const std::optional<DecodedScan> scan = decode_and_smooth(capture, how.decode, no_smoothing);
    if (!scan)
        return std::nullopt;
    const TableCloud made = apply_table_to_scan(*table, scan->decoded, how.decode.threads);
    if (made.stats.points == 0)
        throw InputError(
            path, "",
            std::to_string(scan->decode_stats.decoded) + " pixels decoded but the table " +
                how.table_path.string() + " gives none a point (no model " +
                std::to_string(made.stats.no_model) + ", outside its phase range " +
                std::to_string(made.stats.out_of_range) + "): is the table for this scanner?");
    try {
        return measure_position(artefact, made.cloud.xyz, path, options, capture_truth(capture));
    } catch (const InputError& e) {
        // A sphere missing or cut where the table has no model is the
        // calibration session's reach, not the artefact's place: say so.
        const std::size_t unmodelled = made.stats.no_model + made.stats.out_of_range;
        const std::size_t decoded = scan->decode_stats.decoded;
        if (e.field().rfind("sphere", 0) != 0 || decoded == 0 || 50 * unmodelled < decoded)
            throw;
        const std::string prefix = e.file().string() + ": " + e.field() + ": ";
        const std::string reason = std::string(e.what()).substr(prefix.size());
        throw InputError(
            e.file(), e.field(),
            reason + "; the table " + how.table_path.string() + " gives no point at " +
                std::to_string(unmodelled) + " of the " + std::to_string(decoded) +
                " decoded pixels (" + fixed_text(100.0 * double(unmodelled) / double(decoded), 1) +
                " %: no model " + std::to_string(made.stats.no_model) +
                ", outside its depth range " + std::to_string(made.stats.out_of_range) +
                "), where the calibration session's boards did not reach: calibrate with boards "
                "there, or place the artefact where the table has a model");
    }
}

std::string position_line(std::size_t k, const MeasuredPosition& p) {
    std::ostringstream s;
    s << "position " << k + 1 << ":";
    if (p.spacing_error)
        s << " length " << fixed_text(*p.length, 4) << " mm, SD " << fixed_text(*p.spacing_error, 4)
          << " mm;";
    for (const MeasuredSphere& sphere : p.spheres)
        s << " sphere " << sphere.index + 1 << " P_F " << fixed_text(sphere.form, 4) << " P_S "
          << fixed_text(sphere.size_error, 4) << " coverage " << fixed_text(sphere.coverage, 2)
          << " (" << sphere.points_used << " points);";
    if (p.plane)
        s << " F " << fixed_text(p.plane->flatness, 4) << " mm (" << p.plane->points_used
          << " points);";
    return s.str();
}

} // namespace fpp::calib
