// fpp-calib scanner-push-table --scanner URL --token-file FILE TABLE.fpt

#include "cli_util.hpp"
#include "commands.hpp"
#include "scanner_connection.hpp"

#include "fpp/coefficient_table.hpp"
#include "fpp/fnv1a.hpp"
#include "fpp/yaml_fields.hpp"

#include <cstdio>
#include <iostream>
#include <memory>

namespace fpp::calib {

namespace {
struct ScannerPushTableArgs {
    ScannerConnectionArgs connection;
    std::string table;
};

// The scanner's spelling of a hash: 16 lowercase hex digits.
std::string hex64(std::uint64_t value) {
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
    return text;
}

// A field of the scanner's answer as text ("?" when it is missing).
std::string field_text(const nlohmann::json& object, const char* key) {
    if (!object.is_object() || !object.contains(key))
        return "?";
    const nlohmann::json& value = object[key];
    return value.is_string() ? value.get<std::string>() : value.dump();
}

std::string size_text(const nlohmann::json& object, const char* key) {
    const nlohmann::json size = object.value(key, nlohmann::json());
    return field_text(size, "width") + " x " + field_text(size, "height");
}

int run_scanner_push_table(const ScannerPushTableArgs& args) {
    const ScannerClient client = connect_to_scanner(args.connection);
    const std::string bytes = yaml_fields::read_text_file(args.table);
    std::cerr << "uploading " << args.table << " (" << bytes.size() << " bytes) to "
              << client.url("/api/v1/table") << "\n";
    nlohmann::json installed;
    try {
        installed = client.put_bytes("/api/v1/table", bytes);
    } catch (const ScannerError& e) {
        if (e.http_status() == 400) // the scanner's loader rejected the file
            throw ScannerError("the scanner refused " + args.table +
                                   " and keeps the table it had: " + e.what(),
                               400);
        throw;
    }
    if (!installed.is_object())
        throw ScannerError("PUT " + client.url("/api/v1/table") +
                           ": the answer is not the installed table's description");
    // The scanner hashes what it installed: the same bytes as the file's.
    const std::string ours = hex64(fnv1a64(bytes.data(), bytes.size()));
    const std::string theirs = field_text(installed, "file_fnv1a64");
    if (theirs != ours)
        throw ScannerError("PUT " + client.url("/api/v1/table") +
                           ": the scanner installed a file "
                           "with file_fnv1a64 " +
                           theirs + ", but " + args.table + "'s is " + ours);
    std::cout << "installed " << args.table << " on " << client.base_url() << " as "
              << field_text(installed, "path") << "\n"
              << "  model " << field_text(installed, "model") << ", camera "
              << size_text(installed, "camera") << ", projector "
              << size_text(installed, "projector") << ", " << field_text(installed, "bytes")
              << " bytes\n"
              << "  file_fnv1a64 " << theirs << ", calibration_fnv1a64 "
              << field_text(installed, "calibration_fnv1a64") << "\n"
              << "  used from the next scan on\n";
    return 0;
}
} // namespace

Action add_scanner_push_table_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<ScannerPushTableArgs>(
        app, "scanner-push-table",
        "Install a coefficient table (.fpt, from `calibrate` or `hybrid`) on a scanner (PUT "
        "/api/v1/table): the scanner checks it against its camera and display, keeps the "
        "previous one beside it and uses the new one from its next scan; a table it refuses "
        "changes nothing",
        run_scanner_push_table);
    add_scanner_connection_options(*cmd, args->connection);
    cmd->add_option("table", args->table, "the table file (.fpt)")
        ->required()
        ->check(CLI::ExistingFile);
    return action;
}

} // namespace fpp::calib
