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

// Owns a POSIX file descriptor; closes it on destruction (errors ignored there:
// paths that care about close() errors call close_checked()).
class UniqueFd {
public:
    explicit UniqueFd(int fd) : fd_(fd) {}
    ~UniqueFd() {
        if (fd_ >= 0) ::close(fd_);
    }
    UniqueFd(const UniqueFd&) = delete;
    UniqueFd& operator=(const UniqueFd&) = delete;
    int get() const { return fd_; }
    bool valid() const { return fd_ >= 0; }
    // Closes now and reports the error (NFS and some FUSE file systems report
    // a failed write-back only here).
    int close_checked() {
        const int fd = fd_;
        fd_ = -1;
        return ::close(fd);
    }

private:
    int fd_;
};

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
            throw IoError(target, describe_errno("cannot create a temporary file in " +
                                                     folder.string(),
                                                 errno));
        }
    }
    throw IoError(target, "cannot find a free temporary file name in " + folder.string());
}

void write_all(int fd, const fs::path& path, std::string_view bytes) {
    const char* p = bytes.data();
    std::size_t left = bytes.size();
    while (left > 0) {
        const ssize_t n = ::write(fd, p, left);
        if (n < 0) {
            if (errno == EINTR) continue;
            throw IoError(path, describe_errno("write failed", errno));
        }
        p += n;
        left -= static_cast<std::size_t>(n);
    }
}

} // namespace

std::string describe_errno(const std::string& what, int err) {
    std::string message = what + ": " + std::strerror(err);
    if (err == ENOSPC) message += " (no space left on the device: the disk is full)";
    if (err == EDQUOT) message += " (disk quota exceeded)";
    return message;
}

void fsync_path(const std::filesystem::path& path) {
    // O_RDONLY is enough for fsync on Linux and is the only way to open a directory.
    UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
    if (!fd.valid()) throw IoError(path, describe_errno("cannot open for fsync", errno));
    while (::fsync(fd.get()) != 0) {
        if (errno == EINTR) continue;
        // Some file systems cannot fsync a directory; the rename is then as
        // durable as that file system makes it.
        if (errno == EINVAL && fs::is_directory(path)) break;
        throw IoError(path, describe_errno("fsync failed", errno));
    }
    if (fd.close_checked() != 0) throw IoError(path, describe_errno("close failed", errno));
}

void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path& temp)>& write) {
    if (target.filename().empty()) throw IoError(target, "not a file name");
    const fs::path temp = create_temp_beside(target);
    try {
        write(temp);
        fsync_path(temp);
        if (std::rename(temp.c_str(), target.c_str()) != 0) {
            throw IoError(target, describe_errno("cannot rename " + temp.string() + " onto it",
                                                 errno));
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
    UniqueFd fd(::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666));
    if (!fd.valid()) throw IoError(path, describe_errno("cannot open for writing", errno));
    write_all(fd.get(), path, bytes);
    while (::fsync(fd.get()) != 0) {
        if (errno == EINTR) continue;
        throw IoError(path, describe_errno("fsync failed", errno));
    }
    if (fd.close_checked() != 0) throw IoError(path, describe_errno("close failed", errno));
}

void write_folder_atomically(const std::filesystem::path& target,
                             const std::function<void(const std::filesystem::path& temp)>& write) {
    if (target.filename().empty()) throw IoError(target, "not a folder name");
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
            throw IoError(target, describe_errno("cannot create a temporary folder in " +
                                                     parent.string(),
                                                 errno));
        }
    }
    if (temp.empty()) throw IoError(target, "cannot find a free temporary folder name");
    try {
        write(temp);
        fsync_path(temp);
        // RENAME_NOREPLACE: renaming a folder onto an existing empty folder
        // would otherwise silently replace it.
        if (::renameat2(AT_FDCWD, temp.c_str(), AT_FDCWD, target.c_str(), RENAME_NOREPLACE) !=
            0) {
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
                throw IoError(target, describe_errno("cannot rename " + temp.string() +
                                                         " onto it",
                                                     errno));
            }
        }
    } catch (...) {
        fs::remove_all(temp, ec);
        throw;
    }
    fsync_path(parent);
}

} // namespace fpp
