#include "fpp/atomic_file.hpp"

#include "fpp/error.hpp"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fpp {

namespace {

namespace fs = std::filesystem;

fs::path folder_of(const fs::path& target) {
    fs::path folder = target.parent_path();
    return folder.empty() ? fs::path(".") : folder;
}

// A name unique within this process and unlikely to clash with another one;
// exclusivity is guaranteed anyway by O_EXCL when the file is created.
std::string unique_suffix() {
    static std::atomic<unsigned> counter{0};
    return std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1));
}

// ".<name><tag><unique>": hidden, and recognisably tied to its target.
std::string hidden_name(const fs::path& target, const char* tag) {
    std::string name(".");
    name += target.filename().string();
    name += tag;
    name += unique_suffix();
    return name;
}

// Creates an empty temporary file beside `target` and returns its path.
fs::path create_temp_beside(const fs::path& target) {
    const fs::path folder = folder_of(target);
    for (int attempt = 0; attempt < 100; ++attempt) {
        fs::path temp = folder / hidden_name(target, ".tmp-");
        const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0) {
            UniqueFd owner(fd);
            if (owner.close_checked() != 0) {
                const int err = errno;
                ::unlink(temp.c_str());
                throw IoError(temp, describe_errno("cannot create temporary file", err));
            }
            return temp;
        }
        if (errno != EEXIST) {
            throw IoError(
                target,
                describe_errno("cannot create a temporary file in " + folder.string(), errno));
        }
    }
    throw IoError(target, "cannot find a free temporary file name in " + folder.string());
}

} // namespace

std::string describe_errno(const std::string& what, int err) {
    std::string message = what + ": " + std::strerror(err);
    if (err == ENOSPC)
        message += " (no space left on the device: the disk is full)";
    if (err == EDQUOT)
        message += " (disk quota exceeded)";
    return message;
}

void fsync_path(const std::filesystem::path& path) {
    // O_RDONLY is enough for fsync on Linux and is the only way to open a directory.
    UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
    if (!fd.valid())
        throw IoError(path, describe_errno("cannot open for fsync", errno));
    while (::fsync(fd.get()) != 0) {
        if (errno == EINTR)
            continue;
        // Some file systems cannot fsync a directory; the rename is then as
        // durable as that file system makes it.
        if (errno == EINVAL && fs::is_directory(path))
            break;
        throw IoError(path, describe_errno("fsync failed", errno));
    }
    if (fd.close_checked() != 0)
        throw IoError(path, describe_errno("close failed", errno));
}

void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path& temp)>& write) {
    if (target.filename().empty())
        throw IoError(target, "not a file name");
    const fs::path temp = create_temp_beside(target);
    try {
        write(temp);
        fsync_path(temp);
        if (std::rename(temp.c_str(), target.c_str()) != 0) {
            throw IoError(target,
                          describe_errno("cannot rename " + temp.string() + " onto it", errno));
        }
    } catch (...) {
        ::unlink(temp.c_str());
        throw;
    }
    fsync_path(folder_of(target));
}

void write_file_atomically(const std::filesystem::path& target, std::string_view bytes) {
    write_atomically(target, [bytes](const fs::path& temp) { write_file_synced(temp, bytes); });
}

void write_file_synced(const std::filesystem::path& path, std::string_view bytes) {
    SyncedFileWriter out(path);
    out.write(bytes);
    out.finish();
}

namespace {
// Written bytes handed to the write-back at a time: large enough for few
// calls, small enough that the disk starts early.
constexpr std::uint64_t kWritebackChunk = std::uint64_t{4} << 20;
} // namespace

SyncedFileWriter::SyncedFileWriter(std::filesystem::path path)
    : path_(std::move(path)),
      fd_(::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666)) {
    if (!fd_.valid())
        throw IoError(path_, describe_errno("cannot open for writing", errno));
}

void SyncedFileWriter::write(std::string_view bytes) {
    if (!fd_.valid())
        throw IoError(path_, "write after finish");
    const char* p = bytes.data();
    std::size_t left = bytes.size();
    while (left > 0) {
        const ssize_t n = ::write(fd_.get(), p, left);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            throw IoError(path_, describe_errno("write failed", errno));
        }
        p += n;
        left -= static_cast<std::size_t>(n);
        written_ += static_cast<std::uint64_t>(n);
    }
#ifdef SYNC_FILE_RANGE_WRITE
    if (written_ - handed_to_writeback_ >= kWritebackChunk) {
        // Only a hint: a file system that refuses it is fsynced as usual, and
        // write-back errors are reported by the fsync in finish().
        (void)::sync_file_range(fd_.get(), static_cast<off_t>(handed_to_writeback_),
                                static_cast<off_t>(written_ - handed_to_writeback_),
                                SYNC_FILE_RANGE_WRITE);
        handed_to_writeback_ = written_;
    }
#endif
}

void SyncedFileWriter::finish() {
    if (!fd_.valid())
        throw IoError(path_, "finished twice");
    while (::fsync(fd_.get()) != 0) {
        if (errno == EINTR)
            continue;
        throw IoError(path_, describe_errno("fsync failed", errno));
    }
    if (fd_.close_checked() != 0)
        throw IoError(path_, describe_errno("close failed", errno));
}

void write_folder_atomically(const std::filesystem::path& target,
                             const std::function<void(const std::filesystem::path& temp)>& write) {
    if (target.filename().empty())
        throw IoError(target, "not a folder name");
    std::error_code ec;
    if (fs::symlink_status(target, ec).type() != fs::file_type::not_found) {
        throw IoError(target, "already exists (a capture folder is never overwritten)");
    }
    const fs::path parent = folder_of(target);
    fs::path temp;
    for (int attempt = 0; attempt < 100 && temp.empty(); ++attempt) {
        fs::path candidate = parent / hidden_name(target, ".partial-");
        if (::mkdir(candidate.c_str(), 0777) == 0) {
            temp = candidate;
        } else if (errno != EEXIST) {
            throw IoError(
                target,
                describe_errno("cannot create a temporary folder in " + parent.string(), errno));
        }
    }
    if (temp.empty())
        throw IoError(target, "cannot find a free temporary folder name");
    try {
        write(temp);
        fsync_path(temp);
        // RENAME_NOREPLACE: renaming a folder onto an existing empty folder
        // would otherwise silently replace it.
        if (::renameat2(AT_FDCWD, temp.c_str(), AT_FDCWD, target.c_str(), RENAME_NOREPLACE) != 0) {
            const int err = errno;
            if (err == EEXIST || err == ENOTEMPTY) {
                throw IoError(target, "already exists (created while the set was written)");
            }
            if (err != EINVAL && err != ENOSYS) {
                throw IoError(target,
                              describe_errno("cannot rename " + temp.string() + " onto it", err));
            }
            // File system without RENAME_NOREPLACE: check, then plain rename.
            if (fs::symlink_status(target, ec).type() != fs::file_type::not_found) {
                throw IoError(target, "already exists (created while the set was written)");
            }
            if (std::rename(temp.c_str(), target.c_str()) != 0) {
                throw IoError(target,
                              describe_errno("cannot rename " + temp.string() + " onto it", errno));
            }
        }
    } catch (...) {
        fs::remove_all(temp, ec);
        throw;
    }
    fsync_path(parent);
}

std::vector<std::string> remove_interrupted_writes(const fs::path& folder,
                                                   const std::string& target_name) {
    std::vector<std::string> removed;
    const std::string prefix = "." + target_name;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
        const std::string name = entry.path().filename().string();
        const std::size_t tag = name.find(".tmp-", prefix.size());
        const std::size_t folder_tag = name.find(".partial-", prefix.size());
        const bool ours =
            name.size() > 1 && name.starts_with(prefix) &&
            (tag != std::string::npos || folder_tag != std::string::npos) &&
            (target_name.empty() || tag == prefix.size() || folder_tag == prefix.size());
        if (!ours)
            continue;
        std::error_code remove_ec;
        fs::remove_all(entry.path(), remove_ec);
        if (remove_ec)
            throw IoError(entry.path(),
                          "cannot remove what an interrupted write left: " + remove_ec.message());
        removed.push_back(name);
    }
    return removed; // a folder that does not exist (yet) holds nothing to remove
}

} // namespace fpp
