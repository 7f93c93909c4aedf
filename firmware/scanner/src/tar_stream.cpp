#include "tar_stream.hpp"

#include "fpp/error.hpp"

#include <archive.h>
#include <archive_entry.h>

#include <algorithm>
#include <cstring>
#include <sys/stat.h>

namespace fpp::scanner {

namespace fs = std::filesystem;

namespace {
constexpr std::size_t kChunk = 64 * 1024;

int no_close(std::FILE*) {
    return 0;
}
} // namespace

std::vector<TarEntry> tar_entries_of(const fs::path& folder, const std::string& prefix) {
    std::vector<TarEntry> entries;
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(folder, ec);
         !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (name.starts_with(".")) { // temporary files of atomic writes
            if (it->is_directory())
                it.disable_recursion_pending();
            continue;
        }
        if (it->is_regular_file())
            entries.push_back(
                {prefix + fs::relative(it->path(), folder).generic_string(), it->path()});
    }
    if (ec)
        throw IoError(folder, "cannot list: " + ec.message());
    std::sort(entries.begin(), entries.end(),
              [](const TarEntry& a, const TarEntry& b) { return a.name < b.name; });
    return entries;
}

TarStream::TarStream(std::vector<TarEntry> entries)
    : entries_(std::move(entries)), archive_(archive_write_new(), &archive_write_free),
      file_(nullptr, &no_close) {
    archive* a = archive_.get();
    if (!a || archive_write_set_format_pax_restricted(a) != ARCHIVE_OK ||
        archive_write_set_bytes_in_last_block(a, 1) != ARCHIVE_OK ||
        archive_write_open2(a, this, nullptr, &TarStream::on_write, nullptr, nullptr) != ARCHIVE_OK)
        throw IoError("tar", a ? archive_error_string(a) : "libarchive: out of memory");
}

TarStream::~TarStream() = default;

la_ssize_t TarStream::on_write(archive*, void* self, const void* data, std::size_t size) {
    auto& s = *static_cast<TarStream*>(self);
    s.pending_.append(static_cast<const char*>(data), size);
    return static_cast<la_ssize_t>(size);
}

// Feeds libarchive one step: a header, a chunk of a file, or the end.
void TarStream::advance() {
    archive* a = archive_.get();
    if (file_) {
        char buffer[kChunk];
        const std::size_t n = std::fread(buffer, 1, sizeof buffer, file_.get());
        if (n > 0) {
            if (archive_write_data(a, buffer, n) < 0)
                throw IoError(entries_[next_entry_ - 1].file, archive_error_string(a));
            return;
        }
        const bool failed = std::ferror(file_.get()) != 0;
        file_.reset();
        if (failed)
            throw IoError(entries_[next_entry_ - 1].file, "read failed");
        if (archive_write_finish_entry(a) != ARCHIVE_OK) // a file that shrank
            throw IoError(entries_[next_entry_ - 1].file, archive_error_string(a));
        return;
    }
    if (next_entry_ == entries_.size()) {
        if (archive_write_close(a) != ARCHIVE_OK)
            throw IoError("tar", archive_error_string(a));
        finished_ = true;
        return;
    }
    const TarEntry& e = entries_[next_entry_++];
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(e.file.c_str(), "rb"),
                                                         &std::fclose);
    struct stat st {};
    if (!file || ::fstat(::fileno(file.get()), &st) != 0)
        throw IoError(e.file, "cannot open for the archive");
    std::unique_ptr<archive_entry, void (*)(archive_entry*)> entry(archive_entry_new(),
                                                                   &archive_entry_free);
    archive_entry_set_pathname(entry.get(), e.name.c_str());
    archive_entry_set_size(entry.get(), st.st_size);
    archive_entry_set_filetype(entry.get(), AE_IFREG);
    archive_entry_set_perm(entry.get(), 0644);
    archive_entry_set_mtime(entry.get(), st.st_mtime, 0);
    if (archive_write_header(a, entry.get()) != ARCHIVE_OK)
        throw IoError(e.file, archive_error_string(a));
    file_ = std::move(file);
}

std::size_t TarStream::read(char* out, std::size_t max) {
    while (offset_ == pending_.size() && !finished_) {
        pending_.clear();
        offset_ = 0;
        advance();
    }
    const std::size_t n = std::min(max, pending_.size() - offset_);
    std::memcpy(out, pending_.data() + offset_, n);
    offset_ += n;
    return n;
}

} // namespace fpp::scanner
