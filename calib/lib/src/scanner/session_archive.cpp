#include "fpp/calib/session_archive.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"
#include "fpp/projector_response.hpp"
#include "fpp/unique_fd.hpp"

#include <archive.h>
#include <archive_entry.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <memory>

namespace fpp::calib {

namespace fs = std::filesystem;

namespace {

struct ArchiveDeleter {
    void operator()(archive* a) const noexcept { archive_read_free(a); }
};
using ArchiveReader = std::unique_ptr<archive, ArchiveDeleter>;

// The entry's path below `session`/ (empty for that folder itself), or an
// InputError naming the entry: nothing may land outside the target.
fs::path path_below_session(const fs::path& tar, const std::string& entry,
                            const std::string& session) {
    if (entry.empty())
        throw InputError(tar, "(an entry without a name)", "refused");
    if (entry.front() == '/')
        throw InputError(tar, entry, "an absolute path: refused");
    const fs::path path(entry);
    if (std::any_of(path.begin(), path.end(), [](const fs::path& part) { return part == ".."; }))
        throw InputError(tar, entry, "a path with '..': refused");
    auto part = path.begin();
    if (*part != session)
        throw InputError(tar, entry, "outside the session's folder " + session + "/: refused");
    fs::path below;
    for (++part; part != path.end(); ++part)
        if (!part->empty() && *part != ".")
            below /= *part;
    return below;
}

[[noreturn]] void archive_failure(archive* a, const fs::path& tar, const std::string& entry) {
    const char* why = archive_error_string(a);
    throw InputError(tar, entry, why ? why : "cannot read the archive");
}

// Copies the current entry's data into the new file `file`; returns its
// size. Not fsynced: the whole folder is, at once, by syncfs.
std::uint64_t copy_entry(archive* a, const fs::path& tar, const std::string& entry,
                         const fs::path& file) {
    UniqueFd out(::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666));
    if (!out.valid())
        throw IoError(file, describe_errno("cannot create", errno));
    std::uint64_t written = 0;
    for (;;) {
        const void* block = nullptr;
        size_t size = 0;
        la_int64_t offset = 0;
        const int status = archive_read_data_block(a, &block, &size, &offset);
        if (status == ARCHIVE_EOF)
            break;
        if (status != ARCHIVE_OK)
            archive_failure(a, tar, entry);
        if (offset < 0 || static_cast<std::uint64_t>(offset) != written)
            throw InputError(tar, entry, "a sparse file: refused");
        for (const char* p = static_cast<const char*>(block); size > 0;) {
            const ssize_t n = ::write(out.get(), p, size);
            if (n < 0 && errno == EINTR)
                continue;
            if (n < 0)
                throw IoError(file, describe_errno("cannot write", errno));
            p += n;
            size -= static_cast<size_t>(n);
            written += static_cast<std::uint64_t>(n);
        }
    }
    if (out.close_checked() != 0)
        throw IoError(file, describe_errno("cannot write", errno));
    return written;
}

} // namespace

ExtractedSession extract_session_tar(const fs::path& tar, const std::string& session,
                                     const fs::path& target) {
    ExtractedSession result;
    write_folder_atomically(target, [&](const fs::path& temp) {
        ArchiveReader reader(archive_read_new());
        if (!reader)
            throw InputError(tar, "", "libarchive: out of memory");
        archive* a = reader.get();
        archive_read_support_format_tar(a);
        if (archive_read_open_filename(a, tar.c_str(), 1 << 16) != ARCHIVE_OK)
            archive_failure(a, tar, "");
        archive_entry* entry = nullptr;
        for (;;) {
            const int status = archive_read_next_header(a, &entry);
            if (status == ARCHIVE_EOF)
                break;
            if (status != ARCHIVE_OK)
                archive_failure(a, tar, "");
            const char* raw_name = archive_entry_pathname(entry);
            const std::string name = raw_name ? raw_name : "";
            const fs::path below = path_below_session(tar, name, session);
            const auto type = archive_entry_filetype(entry);
            if (type == AE_IFDIR) {
                fs::create_directories(temp / below);
            } else if (type == AE_IFREG && archive_entry_hardlink(entry) == nullptr) {
                if (below.empty())
                    throw InputError(tar, name, "a file in place of the session's folder");
                fs::create_directories(temp / below.parent_path());
                result.bytes += copy_entry(a, tar, name, temp / below);
                ++result.files;
            } else {
                throw InputError(tar, name, "neither a file nor a folder (a link?): refused");
            }
        }
        if (!fs::is_regular_file(temp / "board.yaml"))
            throw InputError(tar, session + "/board.yaml",
                             "missing: the archive is not a calibration session");
        // Every file and folder on the disk before the folder is renamed
        // into place: one syncfs rather than an fsync per file (a session
        // is about a thousand files).
        const UniqueFd folder(::open(temp.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
        if (!folder.valid() || ::syncfs(folder.get()) != 0)
            throw IoError(temp, describe_errno("cannot sync to disk", errno));
        // Poses are the folders of scans; response/ holds the projector's
        // response ramp (fpp/projector_response.hpp), not a pose.
        for (const auto& item : fs::directory_iterator(temp))
            if (item.is_directory() && item.path().filename() != kSessionResponseFolder)
                result.poses.push_back(item.path().filename().string());
        std::sort(result.poses.begin(), result.poses.end());
    });
    return result;
}

} // namespace fpp::calib
