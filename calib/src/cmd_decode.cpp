// fpp-calib decode CAPTURE --out DIR [--correct-phase-error]
//
// Exit status: 0 decoded; 2 bad input (named file and field); 3 the decode
// failed (nearly nothing decoded, or the capture's description is evidently
// wrong: fpp/decode_diagnosis.hpp); 5 the decoded field is inconsistent with
// itself (a wrong description that still decodes: fpp/decode_consistency.hpp;
// --accept-inconsistent makes it a warning); the outputs and decode.md are
// written all the same, so the user can look; 1 other errors.

#include "cli_util.hpp"
#include "commands.hpp"
#include "decode_outputs.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/decode_consistency.hpp"
#include "fpp/decode_diagnosis.hpp"
#include "fpp/decode_report.hpp"
#include "fpp/decoder.hpp"
#include "fpp/error.hpp"

#include <iostream>
#include <memory>
#include <stdexcept>

namespace fpp::calib {

namespace {
struct DecodeArgs {
    std::string capture;
    std::string out;
    DecodeOptions options;
    bool accept_inconsistent = false;
};

int run_decode(const DecodeArgs& args) {
    check_decode_options(args.options);
    std::cerr << "reading " << args.capture << "\n";
    const CaptureSet capture =
        read_capture_set(args.capture); // validates before anything is written
    Stopwatch watch;
    // A sequence the decoder cannot decode: InputError naming capture.yaml's field.
    const DecodeResult result = decode(capture, args.options);
    const double seconds = watch.seconds();
    const DecodeStatistics stats = decode_statistics(result, frames_full_scale(capture));
    const DecodeDiagnosis diagnosis = diagnose_decode(capture, result, stats, args.options);
    const std::filesystem::path out = args.out;
    write_decode_images(out, result, capture.manifest);
    const DecodeConsistency consistency =
        check_decode_consistency(result, capture.manifest.sequence);
    const std::string summary =
        decode_summary(result, capture, stats, diagnosis, seconds) + consistency_text(consistency);
    write_file_atomically(out / "decode.md", summary);
    std::cout << summary << "\noutputs in " << out.string() << "\n";
    if (diagnosis.failed) {
        std::cerr << "fpp-calib: error: " << capture.folder.string() << ": " << diagnosis.message
                  << "\n(the outputs and decode.md are written for inspection)\n";
        return kExitDecodeFailed;
    }
    if (!diagnosis.message.empty())
        std::cerr << "fpp-calib: warning: " << diagnosis.message << "\n";
    if (consistency.inconsistent) {
        std::cerr << "fpp-calib: " << (args.accept_inconsistent ? "warning: " : "error: ")
                  << capture.folder.string()
                  << ": the decode is inconsistent: " << consistency.message << "\n";
        if (!args.accept_inconsistent) {
            std::cerr << "(the outputs and decode.md are written for inspection; "
                         "--accept-inconsistent to take them as they are)\n";
            return kExitInconsistent;
        }
    }
    return 0;
}
} // namespace

Action add_decode_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<DecodeArgs>(
        app, "decode",
        "Decode a capture set (ours, simulated or third-party) into projector "
        "coordinate maps: proj_x.tiff, proj_y.tiff, modulation.tiff, mask.png, "
        "flags.png, false-colour PNGs and decode.md (coverage of the lit pixels, "
        "counts per reason a pixel was dropped, the field's consistency). Exits 3, after "
        "writing them, when nearly nothing decoded or the capture's description is evidently "
        "wrong, with the likely cause; 5 when nearly everything decoded but the field is "
        "inconsistent with itself (a reversed shift, a phase or code offset off), naming the "
        "field to check",
        run_decode);
    cmd->add_option("capture", args->capture, "capture set folder (holding capture.yaml)")
        ->required()
        ->check(CLI::ExistingDirectory);
    cmd->add_option("--out", args->out, "output folder (created if needed)")->required();
    add_min_modulation_option(*cmd, args->options.min_modulation);
    add_threads_option(*cmd, args->options.threads);
    cmd->add_flag("--accept-inconsistent", args->accept_inconsistent,
                  "exit 0 (with a warning) when the decoded field is inconsistent with itself");
    cmd->add_flag("--correct-phase-error", args->options.correct_phase_error,
                  "remove, from the capture alone, the periodic phase error a non-linear "
                  "projector response leaves (for captures whose response was never measured; "
                  "the result is reported in decode.md)");
    return action;
}

} // namespace fpp::calib
