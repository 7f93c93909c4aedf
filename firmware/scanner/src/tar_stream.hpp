#pragma once
// A tar archive (POSIX pax) of files on disk, produced piece by piece as an
// HTTP response is sent, so that a whole calibration session (a gigabyte at
// full size) needs neither memory nor a temporary file. libarchive writes the
// format; this pulls it through a small buffer.
#include "fpp/scanner/http_server.hpp"

#include <archive.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

struct archive;

namespace fpp::scanner {

struct TarEntry {
    std::string name;           // path inside the archive, '/'-separated, relative
    std::filesystem::path file; // a regular file
};

// Every regular file under `folder` (sorted, recursively), named `prefix`
// followed by its path relative to `folder`.
std::vector<TarEntry> tar_entries_of(const std::filesystem::path& folder,
                                     const std::string& prefix);

class TarStream final : public HttpStream {
public:
    explicit TarStream(std::vector<TarEntry> entries);
    ~TarStream() override;
    // Throws IoError when a file cannot be read (removed meanwhile, say).
    std::size_t read(char* out, std::size_t max) override;

private:
    void advance();
    static la_ssize_t on_write(archive*, void* self, const void* data, std::size_t size);
    std::vector<TarEntry> entries_;
    std::size_t next_entry_ = 0;
    std::unique_ptr<archive, int (*)(archive*)> archive_;
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_;
    std::string pending_; // archive bytes not yet handed out
    std::size_t offset_ = 0;
    bool finished_ = false;
};

} // namespace fpp::scanner
