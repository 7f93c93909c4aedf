#include "scanner_connection.hpp"

#include "fpp/error.hpp"

#include <algorithm>
#include <cstdlib>

namespace fpp::calib {

void add_scanner_connection_options(CLI::App& command, ScannerConnectionArgs& args) {
    command
        .add_option("--scanner", args.scanner,
                    "the scanner's HTTP API, http://HOST:PORT (as in its board file's `http` "
                    "section or its --http)")
        ->envname("FPP_SCANNER")
        ->required();
    command
        .add_option("--token-file", args.token_file,
                    "file whose first line is the scanner's API token (without it, the token "
                    "itself from env FPP_SCANNER_TOKEN)")
        ->check(CLI::ExistingFile);
}

ScannerClient connect_to_scanner(const ScannerConnectionArgs& args) {
    if (!args.token_file.empty())
        return ScannerClient(args.scanner, read_scanner_token(args.token_file));
    const char* token = std::getenv("FPP_SCANNER_TOKEN");
    if (!token || !*token)
        throw std::invalid_argument("no API token: give --token-file FILE (the token on its "
                                    "first line) or set FPP_SCANNER_TOKEN");
    return ScannerClient(args.scanner, token);
}

void check_session_name(const std::string& name) {
    const auto allowed = [](char c) {
        return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
               c == '.' || c == '_' || c == '-';
    };
    if (name.empty() || name.size() > 64 || name.front() == '.' ||
        !std::all_of(name.begin(), name.end(), allowed))
        throw std::invalid_argument("session name \"" + name +
                                    "\": expected 1 to 64 of A-Z a-z 0-9 . _ -, not starting "
                                    "with '.'");
}

std::filesystem::path new_output_folder(std::string folder) {
    while (folder.size() > 1 && folder.back() == '/')
        folder.pop_back();
    const std::filesystem::path out = folder;
    std::error_code ec;
    if (std::filesystem::symlink_status(out, ec).type() != std::filesystem::file_type::not_found)
        throw InputError(out, "", "already exists; --out names a new folder");
    const std::filesystem::path parent =
        out.has_parent_path() ? out.parent_path() : std::filesystem::path(".");
    if (!std::filesystem::is_directory(parent, ec))
        throw InputError(out, "", "its folder " + parent.string() + " does not exist");
    return out;
}

} // namespace fpp::calib
