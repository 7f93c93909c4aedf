#include "fpp/scanner/scan_store.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <system_error>
#include <unistd.h>

namespace fpp::scanner {

namespace fs = std::filesystem;

void prepare_store(const fs::path& directory) {
    std::error_code ec;
    fs::create_directories(directory, ec);
    if (ec)
        throw IoError(directory, "cannot create the scan store: " + ec.message());
    if (::access(directory.c_str(), W_OK | X_OK) != 0)
        throw IoError(directory, describe_errno("scan store not writable", errno));
}

fs::path new_scan_folder(const fs::path& directory) {
    return new_scan_folder(directory, std::chrono::system_clock::now());
}

fs::path new_scan_folder(const fs::path& directory, std::chrono::system_clock::time_point now) {
    const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
    const auto ms =
        std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() %
        1000;
    std::tm utc{};
    gmtime_r(&seconds, &utc);
    char name[64];
    std::snprintf(name, sizeof name, "scan-%04d%02d%02d-%02d%02d%02d-%03d", utc.tm_year + 1900,
                  utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec,
                  static_cast<int>(ms));
    // Names must sort after every scan in the store, or pruning (oldest
    // name first) would remove the newest scans: when the clock went back
    // (or two scans share a millisecond) the newest name's time is kept and
    // a 6-digit sequence number counts on.
    const auto scans = list_scans(directory);
    if (scans.empty() || scans.back().filename().string() < name)
        return directory / name;
    const std::string newest = scans.back().filename().string();
    constexpr std::size_t kTimeLength = 24; // scan-YYYYMMDD-HHMMSS-mmm
    long sequence = 1;
    if (newest.size() > kTimeLength + 1 && newest[kTimeLength] == '-') {
        const std::string digits = newest.substr(kTimeLength + 1);
        if (digits.size() <= 6 &&
            std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
            sequence = std::stol(digits);
    }
    if (sequence >= 999999)
        throw IoError(directory, "a million scans named after " + newest.substr(0, kTimeLength) +
                                     " (the clock is behind the store's newest scan)");
    char suffix[24];
    std::snprintf(suffix, sizeof suffix, "-%06ld", sequence + 1);
    return directory / (newest.substr(0, kTimeLength) + suffix);
}

std::vector<std::string> remove_interrupted_scans(const fs::path& directory) {
    std::vector<std::string> removed = remove_interrupted_writes(directory);
    std::error_code ec;
    for (const auto& session : fs::directory_iterator(directory / "sessions", ec))
        if (session.is_directory())
            for (const auto& name : remove_interrupted_writes(session.path()))
                removed.push_back("sessions/" + session.path().filename().string() + "/" + name);
    return removed;
}

std::vector<fs::path> list_scans(const fs::path& directory) {
    std::vector<fs::path> scans;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(directory, ec))
        if (entry.is_directory() && entry.path().filename().string().starts_with("scan-"))
            scans.push_back(entry.path());
    std::sort(scans.begin(), scans.end());
    return scans;
}

std::uint64_t folder_bytes(const fs::path& folder) {
    // A DELETE, the pruning or a scan's write (its temporary folder renamed
    // into place) may remove a file or a folder between the listing and its
    // size or the descent into it: it then counts as nothing. (A recursive
    // directory iterator throws from its increment when a folder it is about
    // to enter is gone.)
    std::uint64_t total = 0;
    std::error_code ec;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
        std::error_code gone;
        const fs::file_status status = it->symlink_status(gone);
        if (fs::is_directory(status)) {
            total += folder_bytes(it->path());
        } else if (fs::is_regular_file(status)) {
            const std::uintmax_t bytes = it->file_size(gone);
            if (!gone)
                total += bytes;
        }
    }
    return total;
}

std::vector<fs::path> prune_store(const fs::path& directory, std::uint64_t max_bytes,
                                  const fs::path& keep) {
    const auto scans = list_scans(directory);
    std::vector<std::uint64_t> sizes;
    std::uint64_t total = 0;
    for (const auto& s : scans)
        total += sizes.emplace_back(folder_bytes(s));
    std::vector<fs::path> removed;
    for (std::size_t i = 0; i < scans.size() && total > max_bytes; ++i) {
        if (scans[i] == keep)
            continue;
        std::error_code ec;
        fs::remove_all(scans[i], ec);
        if (ec)
            throw IoError(scans[i], "cannot prune: " + ec.message());
        total -= sizes[i];
        removed.push_back(scans[i]);
    }
    return removed;
}

} // namespace fpp::scanner
