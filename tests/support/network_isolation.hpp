#pragma once
// For test programs that run Aravis's fake GigE camera (it binds the GVCP
// port on 127.0.0.1): define one `const fpp::test::NetworkIsolation
// isolation;` at namespace scope, so that it runs before main() while the
// process has one thread. The process (and every child it starts) gets a
// network namespace of its own; where that is not permitted, a lock file
// serialises the programs instead.
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <fpp/drivers/aravis_fake_camera.hpp>

namespace fpp::test {

struct NetworkIsolation {
    bool namespaced = fpp::drivers::enter_private_network_namespace();
    int lock_fd = -1;
    NetworkIsolation() {
        if (namespaced)
            return;
        lock_fd = open("/tmp/fpp-aravis-fake-camera.lock", O_RDWR | O_CREAT | O_CLOEXEC, 0666);
        if (lock_fd >= 0)
            flock(lock_fd, LOCK_EX);
    }
    ~NetworkIsolation() {
        if (lock_fd >= 0)
            close(lock_fd);
    }
    NetworkIsolation(const NetworkIsolation&) = delete;
    NetworkIsolation& operator=(const NetworkIsolation&) = delete;
};

} // namespace fpp::test
