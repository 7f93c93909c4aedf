#pragma once
// Owner of a POSIX file descriptor. The destructor closes it and ignores an
// error there; code that must see close() errors (NFS and some FUSE file
// systems report a failed write-back only at close) calls close_checked().

#include <utility>

#include <unistd.h>

namespace fpp {

class UniqueFd {
public:
    UniqueFd() = default;
    explicit UniqueFd(int fd) : fd_(fd) {}
    UniqueFd(UniqueFd&& other) noexcept : fd_(other.release()) {}
    UniqueFd& operator=(UniqueFd&& other) noexcept {
        reset(other.release());
        return *this;
    }
    UniqueFd(const UniqueFd&) = delete;
    UniqueFd& operator=(const UniqueFd&) = delete;
    ~UniqueFd() { reset(); }

    int get() const { return fd_; }
    bool valid() const { return fd_ >= 0; }
    int release() { return std::exchange(fd_, -1); }
    void reset(int fd = -1) {
        if (fd_ >= 0)
            ::close(fd_);
        fd_ = fd;
    }
    // Closes now and returns close()'s result (errno set on failure).
    int close_checked() { return ::close(std::exchange(fd_, -1)); }

private:
    int fd_ = -1;
};

} // namespace fpp
