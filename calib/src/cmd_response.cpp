// fpp-calib response RAMP_FOLDER_OR_SESSION --out response.yaml
//
// Fits the projector's response from a ramp of grey levels
// (firmware/core/formats/response-ramp.md) and writes it
// (firmware/core/formats/projector-response.md) for the board file's
// projector_response.

#include "calibration_outputs.hpp"
#include "cli_util.hpp"
#include "commands.hpp"
#include "response_fit.hpp"

#include "fpp/error.hpp"

#include <iostream>
#include <memory>

namespace fpp::calib {

namespace {
struct ResponseArgs {
    std::string input;
    std::string out;
};

int run_response(const ResponseArgs& args) {
    const std::filesystem::path out = args.out;
    check_output_file(out, "--out names the response file to write");
    const std::optional<std::filesystem::path> ramp = find_response_ramp(args.input);
    if (!ramp)
        throw InputError(args.input, "",
                         "holds neither ramp.yaml (a response ramp) nor response/ramp.yaml (a "
                         "calibration session with one)");
    const ProjectorResponse response = fit_and_report_response(*ramp, std::cout);
    save_projector_response(out, response);
    std::cout << "wrote " << out.string() << "\n";
    return 0;
}
} // namespace

Action add_response_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<ResponseArgs>(
        app, "response",
        "Fit the projector's response (the light of each 8-bit drive level, black level removed, "
        "full light 1) from a ramp of grey levels on the board, and write it "
        "(fpp-projector-response/1) for the board file's projector_response: the scanner then "
        "renders its patterns through its inverse",
        run_response);
    cmd->add_option("ramp", args->input,
                    "a response ramp folder (ramp.yaml) or a calibration session holding one in "
                    "response/")
        ->required();
    cmd->add_option("--out", args->out, "response file to write (YAML)")->required();
    return action;
}

} // namespace fpp::calib
