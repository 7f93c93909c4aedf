#include "scanner_pull.hpp"

#include "cli_util.hpp"

#include <unistd.h>

#include <cstdio>
#include <iostream>

namespace fpp::calib {

namespace {
// The downloaded tar, removed when the pull ends however it ends.
struct TemporaryFile {
    std::filesystem::path path;
    ~TemporaryFile() {
        std::error_code ignored;
        std::filesystem::remove(path, ignored);
    }
};

std::string megabytes(std::uint64_t bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f MB", static_cast<double>(bytes) / 1e6);
    return text;
}
} // namespace

ExtractedSession pull_scanner_session(const ScannerClient& client, const std::string& session,
                                      const std::filesystem::path& out) {
    const std::string path = "/api/v1/sessions/" + session + "/session.tar";
    const std::filesystem::path folder =
        out.has_parent_path() ? out.parent_path() : std::filesystem::path(".");
    // Built by appending: GCC 12 at -O3 warns (-Wrestrict, falsely) about
    // "." + std::string.
    std::string tar_name(".");
    tar_name += out.filename().string();
    tar_name += ".session-" + std::to_string(::getpid()) + ".tar";
    const TemporaryFile tar{folder / tar_name};
    std::cerr << "downloading " << client.url(path) << "\n";
    Stopwatch watch;
    const std::uint64_t bytes = client.download(path, tar.path);
    std::cerr << "downloaded " << megabytes(bytes) << " in " << seconds_text(watch.seconds())
              << "\n";
    ExtractedSession extracted = extract_session_tar(tar.path, session, out);
    std::cout << "session " << session << ": " << extracted.poses.size() << " poses ("
              << extracted.files << " files, " << megabytes(extracted.bytes) << ") in "
              << out.string() << "\n";
    return extracted;
}

} // namespace fpp::calib
