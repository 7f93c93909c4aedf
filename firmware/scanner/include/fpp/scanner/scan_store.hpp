#pragma once
// The scan store: one folder per scan (scan-YYYYMMDD-HHMMSS-mmm, UTC, so that
// names sort by time) under one directory, pruned oldest first to a size limit.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace fpp::scanner {

// Creates the store directory if needed and checks that it is writable
// (throws IoError otherwise).
void prepare_store(const std::filesystem::path& directory);

// A folder name for a scan starting now that does not exist yet and sorts
// after every scan in the store, even when the clock went back: then the
// newest scan's time with a sequence number (scan-...-mmm-000002, -000003).
std::filesystem::path new_scan_folder(const std::filesystem::path& directory);
std::filesystem::path new_scan_folder(const std::filesystem::path& directory,
                                      std::chrono::system_clock::time_point now);

// At the scanner's start: removes what scans cut short by a power cut or
// SIGKILL left in the store and its sessions (hidden temporaries of
// fpp/atomic_file.hpp) and returns their paths relative to the store.
std::vector<std::string> remove_interrupted_scans(const std::filesystem::path& directory);

// Scan folders in the store, oldest first.
std::vector<std::filesystem::path> list_scans(const std::filesystem::path& directory);

// Bytes held by the files under `folder` (0 for a missing folder; a file
// removed while counting counts as 0).
std::uint64_t folder_bytes(const std::filesystem::path& folder);

// Removes the oldest scans until the store holds at most `max_bytes`, never
// removing `keep`. Returns the folders removed.
std::vector<std::filesystem::path> prune_store(const std::filesystem::path& directory,
                                               std::uint64_t max_bytes,
                                               const std::filesystem::path& keep);

} // namespace fpp::scanner
