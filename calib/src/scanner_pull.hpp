#pragma once
// Fetching a calibration session from the scanner as a session folder
// (`scanner-pull`, and the end of `scanner-session`).

#include "fpp/calib/scanner_client.hpp"
#include "fpp/calib/session_archive.hpp"

#include <filesystem>
#include <string>

namespace fpp::calib {

// Downloads GET /api/v1/sessions/NAME/session.tar beside `out` and unpacks
// it into the new folder `out` (board.yaml and one folder per pose), which
// appears whole or not at all; the tar is removed either way. Prints
// progress on stderr and the result on stdout.
ExtractedSession pull_scanner_session(const ScannerClient& client, const std::string& session,
                                      const std::filesystem::path& out);

} // namespace fpp::calib
