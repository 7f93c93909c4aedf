// The owner of a file descriptor (fpp/unique_fd.hpp): it closes what it owns
// once, on destruction, reset or close_checked, and never what it has given
// away by release() or a move.

#include "fpp/unique_fd.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <utility>

#include <fcntl.h>
#include <unistd.h>

namespace {

using fpp::UniqueFd;

bool is_open(int fd) {
    return ::fcntl(fd, F_GETFD) != -1;
}

// A pipe's two ends, owned.
struct Pipe {
    UniqueFd read, write;
    Pipe() {
        int fds[2];
        if (::pipe(fds) == 0) {
            read.reset(fds[0]);
            write.reset(fds[1]);
        }
    }
};

TEST(UniqueFd, EmptyByDefaultAndClosesWhatItOwnsOnDestruction) {
    const UniqueFd none;
    EXPECT_FALSE(none.valid());
    EXPECT_EQ(none.get(), -1);
    int fd = -1;
    {
        Pipe p;
        ASSERT_TRUE(p.read.valid() && p.write.valid());
        fd = p.read.get();
        EXPECT_TRUE(is_open(fd));
    }
    EXPECT_FALSE(is_open(fd));
}

TEST(UniqueFd, MovingHandsOverOwnershipAndMoveAssignmentClosesTheOldOne) {
    Pipe p;
    const int r = p.read.get(), w = p.write.get();
    UniqueFd moved(std::move(p.read));
    EXPECT_EQ(moved.get(), r);
    EXPECT_FALSE(p.read.valid()); // NOLINT(bugprone-use-after-move): its state is specified
    EXPECT_TRUE(is_open(r));
    moved = std::move(p.write); // r closed, w now owned by `moved`
    EXPECT_FALSE(is_open(r));
    EXPECT_EQ(moved.get(), w);
    EXPECT_TRUE(is_open(w));
}

TEST(UniqueFd, ReleaseGivesTheDescriptorAwayWithoutClosingIt) {
    int fd = -1;
    {
        Pipe p;
        fd = p.write.release();
        EXPECT_FALSE(p.write.valid());
    }
    EXPECT_TRUE(is_open(fd));
    EXPECT_EQ(::close(fd), 0);
}

TEST(UniqueFd, ResetClosesTheOldDescriptorAndTakesTheNew) {
    Pipe p;
    const int r = p.read.get();
    const int w = p.write.release();
    p.read.reset(w);
    EXPECT_FALSE(is_open(r));
    EXPECT_EQ(p.read.get(), w);
    p.read.reset();
    EXPECT_FALSE(p.read.valid());
    EXPECT_FALSE(is_open(w));
}

TEST(UniqueFd, CloseCheckedReportsCloseResult) {
    Pipe p;
    const int fd = p.read.get();
    EXPECT_EQ(p.read.close_checked(), 0);
    EXPECT_FALSE(p.read.valid());
    EXPECT_FALSE(is_open(fd));
    // Nothing owned: close(-1), which fails with EBADF.
    errno = 0;
    EXPECT_EQ(p.read.close_checked(), -1);
    EXPECT_EQ(errno, EBADF);
}

} // namespace
