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

#include "capture_measurement.hpp"
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

int run_verify(const VerifyArgs& args) {
    check_decode_options(args.decode);
    VerificationRecord record;
    record.options = check_verify_arguments(args);
    record.artefact = read_artefact(args.artefact);
    record.table = args.table;
    check_mpe_fits_artefact(record.artefact, record.options);
    if (!fs::is_regular_file(args.table))
        throw InputError(args.table, "--table", "no such file");
    CaptureMeasurement how;
    how.table_path = args.table;
    how.table_hash = args.any_table ? 0 : file_hash(args.table);
    how.decode = args.decode;

    std::optional<CoefficientTable> table;
    for (std::size_t k = 0; k < args.captures.size(); ++k) {
        std::cerr << "position " << k + 1 << " of " << args.captures.size() << ": "
                  << args.captures[k] << "\n";
        std::optional<MeasuredPosition> position =
            measure_capture(args.captures[k], how, record.artefact, table, record.options);
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
    add_min_modulation_option(*cmd, args->decode.min_modulation);
    add_threads_option(*cmd, args->decode.threads);
    return action;
}

} // namespace fpp::calib
