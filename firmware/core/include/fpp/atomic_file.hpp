#pragma once
// Crash-safe output: write to a temporary file next to the target, fsync it,
// rename it over the target, fsync the directory. A reader never sees a
// half-written file.

#include "fpp/unique_fd.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace fpp {

// A file written in pieces, then fsynced. Each few MiB written are handed to
// the kernel's write-back at once (Linux sync_file_range), so that the disk
// works while the caller makes the next pieces and finish() waits only for
// the last ones rather than for the whole file.
class SyncedFileWriter {
public:
    // Creates or truncates `path`. Throws IoError.
    explicit SyncedFileWriter(std::filesystem::path path);
    // Throws IoError (a full disk is named as such).
    void write(std::string_view bytes);
    // fsync, then close (both checked). Throws IoError. A writer destroyed
    // without finish() just closes its file.
    void finish();

private:
    std::filesystem::path path_;
    UniqueFd fd_;
    std::uint64_t written_ = 0;
    std::uint64_t handed_to_writeback_ = 0;
};

// Calls `write` with the path of a fresh temporary file in the target's
// folder, then fsyncs and renames it to `target`. On any exception the
// temporary file is removed and the exception propagates.
void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path& temp)>& write);

// Convenience for text and byte buffers.
void write_file_atomically(const std::filesystem::path& target, std::string_view bytes);

// fsync a file or directory by path (throws IoError on failure).
void fsync_path(const std::filesystem::path& path);

// Writes `bytes` straight to `path` (created or truncated) and fsyncs it, with
// no temporary file: for files inside a folder that is published as a whole by
// write_folder_atomically. Throws IoError.
void write_file_synced(const std::filesystem::path& path, std::string_view bytes);

// Folder counterpart of write_atomically: calls `write` with a fresh empty
// temporary folder beside `target`, fsyncs it, then renames it to `target`,
// which must not exist (IoError otherwise, also if it appears meanwhile). On
// any exception the temporary folder and its contents are removed. `write`
// must fsync the files it creates (write_file_synced and the *_synced image
// writers do).
void write_folder_atomically(const std::filesystem::path& target,
                             const std::function<void(const std::filesystem::path& temp)>& write);

// Removes what writes cut short by a power cut or SIGKILL left in `folder`
// (the hidden ".NAME.tmp-*" files and ".NAME.partial-*" folders of the two
// functions above; nothing else; with `target_name`, only those of that
// target) and returns their names. Only for a folder no one is writing to:
// at a program's start. Throws IoError when one cannot be removed.
std::vector<std::string> remove_interrupted_writes(const std::filesystem::path& folder,
                                                   const std::string& target_name = {});

// "what: strerror(err)", with a plain explanation added for a full disk.
std::string describe_errno(const std::string& what, int err);

} // namespace fpp
