// fpp-calib scanner-status --scanner URL --token-file FILE

#include "commands.hpp"
#include "scanner_connection.hpp"

#include <iostream>
#include <memory>

namespace fpp::calib {

Action add_scanner_status_command(CLI::App& app) {
    auto args = std::make_shared<ScannerConnectionArgs>();
    auto* cmd = app.add_subcommand(
        "scanner-status", "Print a scanner's status (GET /api/v1/status of fpp-scanner's HTTP "
                          "API): state, camera, display, installed table, store, last scan");
    add_scanner_connection_options(*cmd, *args);
    return [args] {
        std::cout << connect_to_scanner(*args).get_json("/api/v1/status").dump(2) << "\n";
        return 0;
    };
}

} // namespace fpp::calib
