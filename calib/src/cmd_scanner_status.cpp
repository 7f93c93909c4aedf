// fpp-calib scanner-status --scanner URL --token-file FILE

#include "cli_util.hpp"
#include "commands.hpp"
#include "scanner_connection.hpp"

#include <iostream>
#include <memory>

namespace fpp::calib {

namespace {
int run_scanner_status(const ScannerConnectionArgs& args) {
    std::cout << connect_to_scanner(args).get_json("/api/v1/status").dump(2) << "\n";
    return 0;
}
} // namespace

Action add_scanner_status_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<ScannerConnectionArgs>(
        app, "scanner-status",
        "Print a scanner's status (GET /api/v1/status of fpp-scanner's HTTP "
        "API): state, camera, display, installed table, store, last scan",
        run_scanner_status);
    add_scanner_connection_options(*cmd, *args);
    return action;
}

} // namespace fpp::calib
