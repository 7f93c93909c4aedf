// Atomic file and folder output: the target appears complete or not at all,
// no temporary file or folder survives a failure, errors carry the path.

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using fpp::test::TempDir;

namespace {

using fpp::test::file_bytes;

std::vector<std::string> listing(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(folder))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

} // namespace

TEST(AtomicFile, WritesAndReplacesWithoutLeftovers) {
    TempDir dir;
    fpp::write_file_atomically(dir / "a.txt", "first");
    EXPECT_EQ(file_bytes(dir / "a.txt"), "first");
    fpp::write_file_atomically(dir / "a.txt", std::string(100000, 'x'));
    EXPECT_EQ(file_bytes(dir / "a.txt"), std::string(100000, 'x'));
    fpp::write_file_atomically(dir / "empty.txt", "");
    EXPECT_EQ(fs::file_size(dir / "empty.txt"), 0u);
    EXPECT_EQ(listing(dir.path()), (std::vector<std::string>{"a.txt", "empty.txt"}));
}

TEST(AtomicFile, CallbackWritesTheTemporaryFileBesideTheTarget) {
    TempDir dir;
    fs::path seen;
    fpp::write_atomically(dir / "out.bin", [&](const fs::path& temp) {
        seen = temp;
        EXPECT_EQ(temp.parent_path(), dir.path());
        EXPECT_NE(temp.filename(), "out.bin");
        EXPECT_TRUE(fs::exists(temp)); // created exclusively before the callback
        EXPECT_FALSE(fs::exists(dir / "out.bin"));
        std::ofstream(temp, std::ios::binary) << "payload";
    });
    EXPECT_FALSE(fs::exists(seen));
    EXPECT_EQ(file_bytes(dir / "out.bin"), "payload");
}

TEST(AtomicFile, ExceptionInCallbackRemovesTemporaryAndKeepsOldTarget) {
    TempDir dir;
    fpp::write_file_atomically(dir / "keep.txt", "old");
    EXPECT_THROW(fpp::write_atomically(dir / "keep.txt",
                                       [](const fs::path& temp) {
                                           std::ofstream(temp) << "half-written";
                                           throw std::runtime_error("encoder failed");
                                       }),
                 std::runtime_error);
    EXPECT_EQ(file_bytes(dir / "keep.txt"), "old");
    EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"keep.txt"});
}

TEST(AtomicFile, MissingFolderIsIoErrorNamingThePath) {
    TempDir dir;
    const fs::path target = dir / "no-such-folder" / "a.txt";
    try {
        fpp::write_file_atomically(target, "x");
        FAIL() << "no error";
    } catch (const fpp::IoError& e) {
        EXPECT_TRUE(contains(e.what(), target.string())) << e.what();
        EXPECT_TRUE(contains(e.what(), "No such file or directory")) << e.what();
    }
    EXPECT_TRUE(listing(dir.path()).empty());
}

TEST(AtomicFile, ParentThatIsAFileIsIoError) {
    TempDir dir;
    fpp::write_file_atomically(dir / "plain", "x");
    EXPECT_THROW(fpp::write_file_atomically(dir / "plain" / "a.txt", "y"), fpp::IoError);
    EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"plain"});
}

TEST(AtomicFile, ReadOnlyFolderIsIoErrorAndLeavesNothing) {
    if (::geteuid() == 0)
        GTEST_SKIP() << "root ignores folder permissions";
    TempDir dir;
    fs::create_directory(dir / "ro");
    fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    EXPECT_THROW(fpp::write_file_atomically(dir / "ro" / "a.txt", "x"), fpp::IoError);
    fs::permissions(dir / "ro", fs::perms::owner_all);
    EXPECT_TRUE(listing(dir / "ro").empty());
}

TEST(AtomicFile, FullDiskSaysNoSpaceLeft) {
    if (!fs::exists("/dev/full"))
        GTEST_SKIP() << "/dev/full not available";
    try {
        fpp::write_file_synced("/dev/full", std::string(8192, 'x'));
        FAIL() << "no error";
    } catch (const fpp::IoError& e) {
        EXPECT_TRUE(contains(e.what(), "/dev/full")) << e.what();
        EXPECT_TRUE(contains(e.what(), "no space left")) << e.what();
    }
    EXPECT_TRUE(contains(fpp::describe_errno("write failed", ENOSPC), "no space left"));
}

// Pieces of all sizes, past the size at which written bytes are handed to
// the write-back, arrive in order; writing after finish() is refused.
TEST(SyncedFileWriter, PiecesArriveInOrderAcrossWritebackChunks) {
    TempDir dir;
    const fs::path path = dir / "pieces.bin";
    std::string expected;
    {
        fpp::SyncedFileWriter out(path);
        for (int i = 0; i < 40; ++i) {
            const std::string piece(static_cast<std::size_t>(1 + i * 37 * 1024),
                                    static_cast<char>('a' + i % 26));
            out.write(piece);
            expected += piece;
        }
        out.finish();
        EXPECT_THROW(out.write("late"), fpp::IoError);
        EXPECT_THROW(out.finish(), fpp::IoError);
    }
    ASSERT_GT(expected.size(), std::size_t{16} << 20);
    EXPECT_TRUE(file_bytes(path) == expected);
    EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"pieces.bin"});
}

TEST(SyncedFileWriter, FullDiskNamesTheFile) {
    if (!fs::exists("/dev/full"))
        GTEST_SKIP() << "/dev/full not available";
    fpp::SyncedFileWriter out("/dev/full");
    try {
        out.write(std::string(8192, 'x'));
        FAIL() << "no error";
    } catch (const fpp::IoError& e) {
        EXPECT_TRUE(contains(e.what(), "/dev/full")) << e.what();
        EXPECT_TRUE(contains(e.what(), "no space left")) << e.what();
    }
}

TEST(SyncedFileWriter, MissingFolderIsIoErrorNamingThePath) {
    TempDir dir;
    try {
        fpp::SyncedFileWriter out(dir / "no" / "such" / "file.bin");
        FAIL() << "no error";
    } catch (const fpp::IoError& e) {
        EXPECT_TRUE(contains(e.what(), "no/such/file.bin")) << e.what();
    }
}

TEST(AtomicFile, FsyncPathWorksOnFilesAndFoldersAndFailsOnMissing) {
    TempDir dir;
    fpp::write_file_atomically(dir / "a", "x");
    EXPECT_NO_THROW(fpp::fsync_path(dir / "a"));
    EXPECT_NO_THROW(fpp::fsync_path(dir.path()));
    EXPECT_THROW(fpp::fsync_path(dir / "missing"), fpp::IoError);
}

TEST(AtomicFile, ConcurrentWritersNeverProduceAMixedFile) {
    TempDir dir;
    const std::string a(200000, 'a');
    const std::string b(200000, 'b');
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t) {
        threads.emplace_back([&, t] {
            for (int i = 0; i < 5; ++i)
                fpp::write_file_atomically(dir / "shared", t % 2 ? a : b);
        });
    }
    for (auto& t : threads)
        t.join();
    const std::string result = file_bytes(dir / "shared");
    EXPECT_TRUE(result == a || result == b);
    EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"shared"});
}

TEST(AtomicFolder, PublishesCompleteFolder) {
    TempDir dir;
    fpp::write_folder_atomically(dir / "set", [](const fs::path& temp) {
        EXPECT_TRUE(fs::is_directory(temp));
        EXPECT_TRUE(fs::is_empty(temp));
        fpp::write_file_synced(temp / "one", "1");
        fpp::write_file_synced(temp / "two", "2");
    });
    EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"set"});
    EXPECT_EQ(listing(dir / "set"), (std::vector<std::string>{"one", "two"}));
}

TEST(AtomicFolder, ExistingTargetIsRefusedAndUntouched) {
    TempDir dir;
    fs::create_directory(dir / "set"); // even an empty folder must not be replaced
    bool called = false;
    try {
        fpp::write_folder_atomically(dir / "set", [&](const fs::path&) { called = true; });
        FAIL() << "no error";
    } catch (const fpp::IoError& e) {
        EXPECT_TRUE(contains(e.what(), (dir / "set").string())) << e.what();
        EXPECT_TRUE(contains(e.what(), "already exists")) << e.what();
    }
    EXPECT_FALSE(called);
    EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"set"});
}

TEST(AtomicFolder, TargetAppearingDuringTheWriteIsNotReplaced) {
    TempDir dir;
    EXPECT_THROW(fpp::write_folder_atomically(dir / "set",
                                              [&](const fs::path& temp) {
                                                  fpp::write_file_synced(temp / "mine", "1");
                                                  fs::create_directory(dir / "set");
                                              }),
                 fpp::IoError);
    EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"set"});
    EXPECT_TRUE(fs::is_empty(dir / "set"));
}

TEST(AtomicFolder, FailureRemovesEverything) {
    TempDir dir;
    EXPECT_THROW(fpp::write_folder_atomically(dir / "set",
                                              [](const fs::path& temp) {
                                                  fpp::write_file_synced(temp / "a", "1");
                                                  fs::create_directory(temp / "sub");
                                                  fpp::write_file_synced(temp / "sub" / "b", "2");
                                                  throw std::runtime_error("camera timeout");
                                              }),
                 std::runtime_error);
    EXPECT_TRUE(listing(dir.path()).empty());
}

TEST(AtomicFolder, MissingParentIsIoError) {
    TempDir dir;
    EXPECT_THROW(fpp::write_folder_atomically(dir / "no" / "set", [](const fs::path&) {}),
                 fpp::IoError);
    EXPECT_TRUE(listing(dir.path()).empty());
}

// A process killed in the middle of an atomic write (a power cut) leaves its
// hidden temporary behind, and never a half-written target; at the next
// start remove_interrupted_writes takes the temporaries and nothing else.
TEST(AtomicFile, WritesCutShortLeaveOnlyTemporariesThatAreRemovedAtStart) {
    TempDir dir;
    fpp::write_file_atomically(dir / "table.fpt", "old table");
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) { // killed while writing a file, then while writing a folder
        const pid_t again = ::fork();
        if (again == 0) {
            fpp::write_atomically(dir / "table.fpt", [](const fs::path& temp) {
                std::ofstream(temp) << "new ta";
                ::kill(::getpid(), SIGKILL);
            });
            _exit(0);
        }
        int status = 0;
        ::waitpid(again, &status, 0);
        fpp::write_folder_atomically(dir / "scan-1", [](const fs::path& temp) {
            fpp::write_file_synced(temp / "cloud.ply", "half a clo");
            ::kill(::getpid(), SIGKILL);
        });
        _exit(0);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status));
    std::ofstream(dir / ".keep") << "not ours";
    std::ofstream(dir / ".notes.tmp") << "not ours either";
    const std::vector<std::string> before = listing(dir.path());
    ASSERT_EQ(before.size(), 5u) << ::testing::PrintToString(before);
    EXPECT_TRUE(before[2].starts_with(".scan-1.partial-")) << before[2];
    EXPECT_TRUE(before[3].starts_with(".table.fpt.tmp-")) << before[3];
    EXPECT_FALSE(fs::exists(dir / "scan-1"));
    EXPECT_EQ(file_bytes(dir / "table.fpt"), "old table");

    // Only another target's: nothing of table.fpt's is touched.
    EXPECT_EQ(fpp::remove_interrupted_writes(dir.path(), "settings.yaml").size(), 0u);
    const auto table_only = fpp::remove_interrupted_writes(dir.path(), "table.fpt");
    ASSERT_EQ(table_only.size(), 1u);
    EXPECT_EQ(table_only[0], before[3]);
    const auto rest = fpp::remove_interrupted_writes(dir.path());
    ASSERT_EQ(rest.size(), 1u);
    EXPECT_EQ(rest[0], before[2]);
    EXPECT_EQ(listing(dir.path()), (std::vector<std::string>{".keep", ".notes.tmp", "table.fpt"}));
    EXPECT_TRUE(fpp::remove_interrupted_writes(dir / "missing").empty());
}
