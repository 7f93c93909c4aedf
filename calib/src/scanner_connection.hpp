#pragma once
// What every command that talks to a scanner takes: where it is and its API
// token, and the checks they share.

#include "fpp/calib/scanner_client.hpp"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <string>

namespace fpp::calib {

struct ScannerConnectionArgs {
    std::string scanner;    // http://HOST:PORT
    std::string token_file; // empty: the token is in FPP_SCANNER_TOKEN
};

// --scanner (env FPP_SCANNER) and --token-file.
void add_scanner_connection_options(CLI::App& command, ScannerConnectionArgs& args);

// The client, its token read from --token-file or FPP_SCANNER_TOKEN.
// Throws InputError or std::invalid_argument when neither gives a good one.
ScannerClient connect_to_scanner(const ScannerConnectionArgs& args);

// A session name as the scanner takes them: 1 to 64 of A-Z a-z 0-9 . _ -,
// not starting with '.'. Checked here too since it goes into URLs.
void check_session_name(const std::string& name);

// `out` (a trailing '/' dropped) after checking that it does not exist and
// its folder does: before the scanner is asked for anything, so that
// nothing is recorded for an output that cannot be written.
std::filesystem::path new_output_folder(std::string out);

} // namespace fpp::calib
