#pragma once
// Subcommands of fpp-calib. Each registers itself on the app and returns the
// action to run when it is the chosen subcommand.

#include <CLI/CLI.hpp>

#include <functional>

namespace fpp::calib {

using Action = std::function<int()>;

Action add_simulate_command(CLI::App& app);
Action add_decode_command(CLI::App& app);
Action add_demo_command(CLI::App& app);
Action add_simulate_session_command(CLI::App& app);
Action add_stereo_command(CLI::App& app);
Action add_session_check_command(CLI::App& app);
Action add_reconstruct_command(CLI::App& app);
Action add_hybrid_command(CLI::App& app);
Action add_calibrate_command(CLI::App& app);
Action add_response_command(CLI::App& app);
Action add_evaluate_command(CLI::App& app);
Action add_verify_command(CLI::App& app);
Action add_correct_command(CLI::App& app);
Action add_paper_experiments_command(CLI::App& app);
Action add_import_command(CLI::App& app);
Action add_patterns_command(CLI::App& app);
// Over a scanner's HTTP API (firmware/scanner/http-api.md).
Action add_scanner_status_command(CLI::App& app);
Action add_scanner_session_command(CLI::App& app);
Action add_scanner_pull_command(CLI::App& app);
Action add_scanner_push_table_command(CLI::App& app);

} // namespace fpp::calib
