// fpp-calib session-check SESSION [--target-um UM] [--suggestions N]
//
// Whether a calibration session is enough for the trueness the user wants,
// and the next pose if not (fpp/calib/session_check.hpp). Exit status: 0
// enough, 3 not yet, 4 too weak for any target; 1 or 2 for errors.

#include "cli_util.hpp"
#include "commands.hpp"
#include "session_check_run.hpp"

#include "fpp/calib/session_check.hpp"

#include <iostream>
#include <memory>

namespace fpp::calib {

namespace {
struct SessionCheckArgs {
    std::string session;
    double target_um = 15;
    int suggestions = 3;
    int threads = 0;
};

int run_session_check(const SessionCheckArgs& args) {
    SessionCheckOptions check;
    check.target_mm = args.target_um / 1000;
    check.suggestions = args.suggestions;
    check.validate();
    const SessionCheck result =
        check_session_folder(args.session, check, args.threads,
                             [](const std::string& line) { std::cerr << line << "\n"; });
    std::cout << result.text();
    return session_check_exit_status(result.verdict);
}
} // namespace

Action add_session_check_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<SessionCheckArgs>(
        app, "session-check",
        "Check a calibration session: calibrate it as `stereo` would, then say what the "
        "calibration's uncertainty means for lengths (1 sigma, 150 mm along depth and across), "
        "how the corners cover the image, the tilts and depths, and whether the target is met; "
        "if not, the next pose that would shrink the depth scale's uncertainty most, in words. "
        "Exit status 0: enough; 3: not yet; 4: too weak for any target",
        run_session_check);
    cmd->add_option("session", args->session, "session folder")->required();
    cmd->add_option("--target-um", args->target_um,
                    "target: 1 sigma of a 150 mm length along depth, at the session's middle "
                    "depth (micrometres)")
        ->capture_default_str();
    cmd->add_option("--suggestions", args->suggestions, "next poses to suggest, best first")
        ->capture_default_str();
    add_threads_option(*cmd, args->threads);
    return action;
}

} // namespace fpp::calib
