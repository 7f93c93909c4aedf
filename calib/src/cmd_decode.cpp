// fpp-calib decode CAPTURE --out DIR [--correct-phase-error]

#include "cli_util.hpp"
#include "commands.hpp"
#include "decode_outputs.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"

#include <iostream>
#include <memory>

namespace fpp::calib {

namespace {
struct DecodeArgs {
    std::string capture;
    std::string out;
    DecodeOptions options;
};

int run_decode(const DecodeArgs& args) {
    args.options.validate();
    std::cerr << "reading " << args.capture << "\n";
    const CaptureSet capture = read_capture_set(args.capture); // validates before anything is written
    Stopwatch watch;
    const DecodeResult result = decode(capture, args.options);
    const double seconds = watch.seconds();
    const std::filesystem::path out = args.out;
    write_decode_images(out, result, capture.manifest);
    const std::string summary = decode_summary(result, capture, seconds);
    write_file_atomically(out / "decode.md", summary);
    std::cout << summary << "\noutputs in " << out.string() << "\n";
    return 0;
}
} // namespace

Action add_decode_command(CLI::App& app) {
    auto args = std::make_shared<DecodeArgs>();
    auto* cmd = app.add_subcommand(
        "decode", "Decode a capture set (ours, simulated or third-party) into projector "
                  "coordinate maps: proj_x.tiff, proj_y.tiff, modulation.tiff, mask.png, "
                  "flags.png, false-colour PNGs and decode.md");
    cmd->add_option("capture", args->capture, "capture set folder (holding capture.yaml)")
        ->required()
        ->check(CLI::ExistingDirectory);
    cmd->add_option("--out", args->out, "output folder (created if needed)")->required();
    cmd->add_option("--min-modulation", args->options.min_modulation,
                    "minimum modulation as a fraction of full scale")
        ->capture_default_str();
    cmd->add_option("--threads", args->options.threads, "worker threads (0 = all cores)")
        ->capture_default_str();
    cmd->add_flag("--correct-phase-error", args->options.correct_phase_error,
                  "remove, from the capture alone, the periodic phase error a non-linear "
                  "projector response leaves (for captures whose response was never measured; "
                  "the result is reported in decode.md)");
    return [args] { return run_decode(*args); };
}

} // namespace fpp::calib
