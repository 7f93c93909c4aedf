// The session tar that fpp-calib pulls from the scanner
// (calib/lib/src/scanner/session_archive.cpp): a good one extracted, and every entry
// that would land outside the folder refused by name with nothing written.
#include "test_support.hpp"

#include "fpp/calib/session_archive.hpp"
#include "fpp/error.hpp"

#include <gtest/gtest.h>

#include <archive.h>
#include <archive_entry.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace fs = std::filesystem;
using fpp::test::TempDir;

namespace {

using fpp::test::file_bytes;

// Names in `folder` that start with a dot (what a failed write leaves).
std::vector<std::string> hidden_entries(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& item : fs::directory_iterator(folder))
        if (item.path().filename().string().front() == '.')
            names.push_back(item.path().filename().string());
    return names;
}

// A tar (pax) of the given entries: name -> contents, or for a name in
// `links`, a symbolic link to its contents.
void write_tar(const fs::path& file, const std::vector<std::pair<std::string, std::string>>& items,
               const std::vector<std::string>& links = {}) {
    archive* a = archive_write_new();
    archive_write_set_format_pax_restricted(a);
    ASSERT_EQ(archive_write_open_filename(a, file.c_str()), ARCHIVE_OK);
    for (const auto& [name, contents] : items) {
        archive_entry* entry = archive_entry_new();
        archive_entry_set_pathname(entry, name.c_str());
        if (std::find(links.begin(), links.end(), name) != links.end()) {
            archive_entry_set_filetype(entry, AE_IFLNK);
            archive_entry_set_symlink(entry, contents.c_str());
            archive_entry_set_size(entry, 0);
        } else {
            archive_entry_set_filetype(entry, AE_IFREG);
            archive_entry_set_size(entry, static_cast<la_int64_t>(contents.size()));
        }
        archive_entry_set_perm(entry, 0644);
        archive_write_header(a, entry);
        if (archive_entry_filetype(entry) == AE_IFREG)
            archive_write_data(a, contents.data(), contents.size());
        archive_entry_free(entry);
    }
    archive_write_close(a);
    archive_write_free(a);
}
} // namespace

TEST(SessionArchive, EntriesThatWouldLandOutsideTheFolderAreRefusedByName) {
    TempDir dir;
    const std::vector<std::pair<std::string, std::string>> good = {
        {"cal/board.yaml", "format: fpp-board/1\n"}, {"cal/scan-1/scan.json", "{}"}};
    write_tar(dir / "good.tar", good);
    const auto extracted = fpp::calib::extract_session_tar(dir / "good.tar", "cal", dir / "good");
    EXPECT_EQ(extracted.poses, std::vector<std::string>{"scan-1"});
    EXPECT_EQ(file_bytes(dir / "good" / "scan-1" / "scan.json"), "{}");

    const std::vector<std::pair<std::string, std::string>> bad = {
        {"/etc/evil", "x"}, {"cal/../evil", "x"}, {"other/evil", "x"}, {"cal/scan-1/link", "/etc"}};
    for (const auto& item : bad) {
        auto items = good;
        items.push_back(item);
        const fs::path tar = dir / "bad.tar", out = dir / "bad";
        write_tar(tar, items, {"cal/scan-1/link"});
        try {
            fpp::calib::extract_session_tar(tar, "cal", out);
            ADD_FAILURE() << item.first << " was taken";
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.field(), item.first) << e.what();
        }
        EXPECT_FALSE(fs::exists(out)) << item.first;
        EXPECT_FALSE(fs::exists(dir / "evil"));
        EXPECT_EQ(hidden_entries(dir.path()), std::vector<std::string>{});
    }
}
