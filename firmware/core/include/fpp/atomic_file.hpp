#pragma once
// Crash-safe output: write to a temporary file next to the target, fsync it,
// rename it over the target, fsync the directory. A reader never sees a
// half-written file.

#include <filesystem>
#include <functional>
#include <string_view>

namespace fpp {

// Calls `write` with the path of a fresh temporary file in the target's
// folder, then fsyncs and renames it to `target`. On any exception the
// temporary file is removed and the exception propagates.
void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path& temp)>& write);

// Convenience for text and byte buffers.
void write_file_atomically(const std::filesystem::path& target, std::string_view bytes);

// fsync a file or directory by path (throws IoError on failure).
void fsync_path(const std::filesystem::path& path);

} // namespace fpp
