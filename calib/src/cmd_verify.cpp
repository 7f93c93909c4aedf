// fpp-calib verify --artefact FILE --table TABLE.fpt --report DIR CAPTURE...
//     [--mpe-sd MM] [--mpe-pf MM] [--mpe-ps MM] [--mpe-flatness MM]
//     [--min-coverage SHARE] [--max-credible-error MM] [--any-table]
//
// Verifies a scanner with a certified artefact after VDI/VDE 2634 part 2:
// each CAPTURE is one position of the artefact, decoded and reconstructed
// with the table exactly as `reconstruct --table` does
// (table_reconstruction.hpp); the artefact is found among whatever else is
// in view and measured (fpp/calib/verification.hpp); the report folder
// (verify_report.hpp) is written whole. Exit status: 0 when every figure
// with an MPE is within it (or none has one), 4 when one is not (the report
// is written and says which), 2 for bad input (nothing written), 3 when a
// capture does not decode.

#include "cli_util.hpp"
#include "commands.hpp"
#include "decode_outputs.hpp"
#include "table_reconstruction.hpp"
#include "verify_report.hpp"

#include "fpp/calib/artefact.hpp"
#include "fpp/calib/plots.hpp"
#include "fpp/calib/report_folder.hpp"
#include "fpp/calib/verification.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

namespace fpp::calib {

namespace {

namespace fs = std::filesystem;

// Exit status when a figure exceeds its MPE (the report is written).
constexpr int kExitVerificationFailed = 4;

struct VerifyArgs {
    std::string artefact, table, report;
    std::vector<std::string> captures;
    double mpe_sd = 0, mpe_pf = 0, mpe_ps = 0, mpe_flatness = 0;
    double min_coverage = VerificationOptions{}.min_coverage;
    double max_credible_error = VerificationOptions{}.max_credible_error_mm;
    bool any_table = false;
    DecodeOptions decode;
    CLI::Option *mpe_sd_option = nullptr, *mpe_pf_option = nullptr, *mpe_ps_option = nullptr,
                *mpe_flatness_option = nullptr;
};

std::optional<double> given_mpe(const CLI::Option* option, double value, const char* name) {
    if (!option || option->count() == 0)
        return std::nullopt;
    if (!(value > 0) || !std::isfinite(value))
        throw InputError("command line", name, "must be a positive length (mm)");
    return value;
}

// Arguments first: bad ones cost nothing and leave nothing behind.
VerificationOptions check_verify_arguments(const VerifyArgs& args) {
    const fs::path report = args.report;
    const fs::path parent = report.lexically_normal().parent_path();
    if (!parent.empty() && !fs::is_directory(parent))
        throw InputError(report, "--report", "the folder " + parent.string() + " does not exist");
    if (!report_folder_writable(report))
        throw InputError(report, "--report",
                         "exists and is not an earlier report (no summary.md); choose another "
                         "folder");
    VerificationOptions options;
    options.mpe.spacing_mm = given_mpe(args.mpe_sd_option, args.mpe_sd, "--mpe-sd");
    options.mpe.form_mm = given_mpe(args.mpe_pf_option, args.mpe_pf, "--mpe-pf");
    options.mpe.size_mm = given_mpe(args.mpe_ps_option, args.mpe_ps, "--mpe-ps");
    options.mpe.flatness_mm =
        given_mpe(args.mpe_flatness_option, args.mpe_flatness, "--mpe-flatness");
    if (!(args.min_coverage > 0 && args.min_coverage < 1))
        throw InputError("command line", "--min-coverage", "must be between 0 and 1");
    if (!(args.max_credible_error > 0) || !std::isfinite(args.max_credible_error))
        throw InputError("command line", "--max-credible-error", "must be a positive length (mm)");
    options.min_coverage = args.min_coverage;
    options.max_credible_error_mm = args.max_credible_error;
    for (std::size_t i = 0; i < args.captures.size(); ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (fs::weakly_canonical(args.captures[i]) == fs::weakly_canonical(args.captures[j]))
                throw InputError(args.captures[i], "",
                                 "given twice (positions " + std::to_string(j + 1) + " and " +
                                     std::to_string(i + 1) + "): each capture is one position");
    return options;
}

// The figures a kind of artefact gives, and the MPE options that fit it.
void check_mpe_fits_artefact(const Artefact& artefact, const VerificationOptions& options) {
    const MaximumPermissibleErrors& mpe = options.mpe;
    const bool plane = artefact.kind == ArtefactKind::plane;
    if (mpe.spacing_mm && artefact.kind != ArtefactKind::ball_bar)
        throw InputError("command line", "--mpe-sd",
                         std::string("a ") + to_string(artefact.kind) + " has no sphere spacing (" +
                             artefact.origin.string() + ")");
    if ((mpe.form_mm || mpe.size_mm) && plane)
        throw InputError("command line", mpe.form_mm ? "--mpe-pf" : "--mpe-ps",
                         "a plane has no sphere (" + artefact.origin.string() + ")");
    if (mpe.flatness_mm && !plane)
        throw InputError("command line", "--mpe-flatness",
                         std::string("a ") + to_string(artefact.kind) + " has no flat (" +
                             artefact.origin.string() + ")");
}

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

// One position: the capture read, checked, decoded, reconstructed, measured.
// Nothing when its decode failed (said on stderr).
std::optional<MeasuredPosition> measure_capture(const VerifyArgs& args, std::size_t k,
                                                const Artefact& artefact,
                                                std::optional<CoefficientTable>& table,
                                                std::uint64_t table_hash,
                                                const VerificationOptions& options) {
    const fs::path path = args.captures[k];
    std::cerr << "position " << k + 1 << " of " << args.captures.size() << ": " << path.string()
              << "\n";
    const CaptureSet capture = read_capture_set(path);
    check_capture_axes(capture, ReconstructAxes::x);
    if (!table)
        table = load_table_for_capture(args.table, capture);
    else
        check_table_fits_capture(*table, args.table, capture);
    if (!args.any_table)
        check_scan_record(path, args.table, table_hash);
    CoordinateFilterOptions no_smoothing;
    no_smoothing.radius = 0;
    const std::optional<DecodedScan> scan = decode_and_smooth(capture, args.decode, no_smoothing);
    if (!scan)
        return std::nullopt;
    const TableCloud made = apply_table_to_scan(*table, scan->decoded, args.decode.threads);
    if (made.stats.points == 0)
        throw InputError(
            path, "",
            std::to_string(scan->decode_stats.decoded) + " pixels decoded but the table " +
                args.table + " gives none a point (no model " +
                std::to_string(made.stats.no_model) + ", outside its phase range " +
                std::to_string(made.stats.out_of_range) + "): is the table for this scanner?");
    return measure_position(artefact, made.cloud.xyz, path, options, capture_truth(capture));
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

int run_verify(const VerifyArgs& args) {
    check_decode_options(args.decode);
    VerificationRecord record;
    record.options = check_verify_arguments(args);
    record.artefact = read_artefact(args.artefact);
    record.table = args.table;
    check_mpe_fits_artefact(record.artefact, record.options);
    if (!fs::is_regular_file(args.table))
        throw InputError(args.table, "--table", "no such file");
    const std::uint64_t table_hash = args.any_table ? 0 : file_hash(args.table);

    std::optional<CoefficientTable> table;
    for (std::size_t k = 0; k < args.captures.size(); ++k) {
        std::optional<MeasuredPosition> position =
            measure_capture(args, k, record.artefact, table, table_hash, record.options);
        if (!position)
            return kExitDecodeFailed;
        std::cerr << position_line(k, *position) << "\n";
        record.positions.push_back(std::move(*position));
    }
    check_certificate(record.artefact, record.positions, record.options);
    record.figures = verdicts(record.artefact, record.positions, record.options.mpe);
    write_verification_report(args.report, record);

    const std::string summary = verification_summary(record);
    std::cout << summary << "\nwrote " << args.report << "\n";
    bool failed = false;
    for (const FigureVerdict& f : record.figures)
        if (!f.passed()) {
            std::cerr << "fpp-calib: verification failed: " << f.name << " reaches "
                      << fixed_text(f.worst, 4) << " mm, beyond its MPE of "
                      << fixed_text(*f.mpe, 4) << " mm\n";
            failed = true;
        }
    return failed ? kExitVerificationFailed : 0;
}

} // namespace

Action add_verify_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<VerifyArgs>(
        app, "verify",
        "Verify the scanner with a certified artefact (VDI/VDE 2634-2): probing errors P_F and "
        "P_S, sphere-spacing error SD, flatness F against their MPEs; writes a report folder; "
        "exit 4 when a figure exceeds its MPE",
        run_verify);
    cmd->add_option("captures", args->captures,
                    "capture set folders, one per position of the artefact, in order")
        ->required();
    cmd->add_option("--artefact", args->artefact,
                    "the artefact's certificate (fpp-artefact/1 YAML: ball-bar, sphere or plane)")
        ->required();
    cmd->add_option("--table", args->table, "coefficient table (.fpt) to verify")->required();
    cmd->add_option("--report", args->report,
                    "report folder to write (must not exist, be empty, or hold an earlier "
                    "report, which is replaced)")
        ->required();
    args->mpe_sd_option =
        cmd->add_option("--mpe-sd", args->mpe_sd, "MPE of the sphere-spacing error SD (mm)");
    args->mpe_pf_option =
        cmd->add_option("--mpe-pf", args->mpe_pf, "MPE of the probing error form P_F (mm)");
    args->mpe_ps_option =
        cmd->add_option("--mpe-ps", args->mpe_ps, "MPE of the probing error size P_S (mm)");
    args->mpe_flatness_option =
        cmd->add_option("--mpe-flatness", args->mpe_flatness, "MPE of the flatness F (mm)");
    cmd->add_option("--min-coverage", args->min_coverage,
                    "least share of a sphere's hemisphere facing the camera that its points "
                    "must cover")
        ->capture_default_str();
    cmd->add_option("--max-credible-error", args->max_credible_error,
                    "a size the scans and the certificate disagree on by more (mm) refuses the "
                    "certificate instead of failing the scanner")
        ->capture_default_str();
    cmd->add_flag("--any-table", args->any_table,
                  "verify the table even on captures whose scan.json names another table");
    cmd->add_option("--min-modulation", args->decode.min_modulation,
                    "minimum modulation as a fraction of full scale")
        ->capture_default_str();
    add_threads_option(*cmd, args->decode.threads);
    return action;
}

} // namespace fpp::calib
