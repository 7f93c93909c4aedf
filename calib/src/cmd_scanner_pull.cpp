// fpp-calib scanner-pull --scanner URL --token-file FILE --session NAME --out DIR

#include "cli_util.hpp"
#include "commands.hpp"
#include "scanner_connection.hpp"
#include "scanner_pull.hpp"

#include <memory>

namespace fpp::calib {

namespace {
struct ScannerPullArgs {
    ScannerConnectionArgs connection;
    std::string session;
    std::string out;
};

int run_scanner_pull(const ScannerPullArgs& args) {
    check_session_name(args.session);
    const std::filesystem::path out = new_output_folder(args.out);
    pull_scanner_session(connect_to_scanner(args.connection), args.session, out);
    return 0;
}
} // namespace

Action add_scanner_pull_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<ScannerPullArgs>(
        app, "scanner-pull",
        "Download a calibration session recorded on a scanner (GET "
        "/api/v1/sessions/NAME/session.tar) into a new session folder for "
        "`calibrate`: board.yaml and one folder per pose",
        run_scanner_pull);
    add_scanner_connection_options(*cmd, args->connection);
    cmd->add_option("--session", args->session, "the session's name on the scanner")->required();
    cmd->add_option("--out", args->out, "the session folder to create (must not exist)")
        ->required();
    return action;
}

} // namespace fpp::calib
