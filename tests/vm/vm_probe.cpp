// vm-probe: checks, inside the virtual ARM board, that the scanner's device
// libraries load and reach the kernel devices the scanner uses:
//   1. DRM/KMS (libdrm): the first connected connector of /dev/dri/card0 is
//      lit with a dumb buffer, then page flips are timed;
//   2. GPIO (libgpiod 1.x): the chip's lines are listed, an output line is
//      driven, and the button line is waited on for a rising edge (the
//      harness presses the button when it reads "vm-probe: waiting for the
//      button" on the console).
// Built by tests/vm/run_vm_probe.sh with the cross compiler; not part of the
// CMake build (of the project it uses only the header-only fpp::UniqueFd).
// Usage: vm-probe [--card PATH] [--chip NAME] [--button N] [--output N]
//                 [--flips N] [--wait-ms N]
// Exit status: 0 when every check passed, 1 otherwise.
#include <fpp/unique_fd.hpp>

#include <gpiod.h>
#include <xf86drm.h>
#include <xf86drmMode.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <memory>
#include <poll.h>
#include <string>
#include <sys/mman.h>
#include <unistd.h>

namespace {

struct Options {
    std::string card = "/dev/dri/card0";
    std::string chip = "gpiochip0";
    unsigned int button = 3; // QEMU virt: the power button's PL061 line
    unsigned int output = 0;
    int flips = 120;
    int wait_ms = 60'000;
};

template <typename T, void (*Free)(T*)> struct Deleter {
    void operator()(T* p) const noexcept { Free(p); }
};
using ResourcesPtr = std::unique_ptr<drmModeRes, Deleter<drmModeRes, drmModeFreeResources>>;
using ConnectorPtr =
    std::unique_ptr<drmModeConnector, Deleter<drmModeConnector, drmModeFreeConnector>>;
using EncoderPtr = std::unique_ptr<drmModeEncoder, Deleter<drmModeEncoder, drmModeFreeEncoder>>;
using ChipPtr = std::unique_ptr<gpiod_chip, Deleter<gpiod_chip, gpiod_chip_close>>;
using LinePtr = std::unique_ptr<gpiod_line, Deleter<gpiod_line, gpiod_line_release>>;

// A dumb buffer with its framebuffer object, filled with one grey level.
class DumbFramebuffer {
public:
    DumbFramebuffer(int fd, std::uint32_t width, std::uint32_t height, std::uint8_t grey)
        : fd_(fd) {
        drm_mode_create_dumb create{};
        create.width = width;
        create.height = height;
        create.bpp = 32;
        if (drmIoctl(fd, DRM_IOCTL_MODE_CREATE_DUMB, &create) != 0)
            return;
        handle_ = create.handle;
        if (drmModeAddFB(fd, width, height, 24, 32, create.pitch, handle_, &fb_) != 0)
            return;
        drm_mode_map_dumb map{};
        map.handle = handle_;
        if (drmIoctl(fd, DRM_IOCTL_MODE_MAP_DUMB, &map) != 0)
            return;
        void* pixels = mmap(nullptr, static_cast<std::size_t>(create.size), PROT_READ | PROT_WRITE,
                            MAP_SHARED, fd, static_cast<off_t>(map.offset));
        if (pixels == MAP_FAILED)
            return;
        std::memset(pixels, grey, static_cast<std::size_t>(create.size));
        munmap(pixels, static_cast<std::size_t>(create.size));
        ok_ = true;
    }
    ~DumbFramebuffer() {
        if (fb_ != 0)
            drmModeRmFB(fd_, fb_);
        if (handle_ != 0) {
            drm_mode_destroy_dumb destroy{};
            destroy.handle = handle_;
            drmIoctl(fd_, DRM_IOCTL_MODE_DESTROY_DUMB, &destroy);
        }
    }
    DumbFramebuffer(const DumbFramebuffer&) = delete;
    DumbFramebuffer& operator=(const DumbFramebuffer&) = delete;
    bool ok() const { return ok_; }
    std::uint32_t id() const { return fb_; }

private:
    int fd_;
    std::uint32_t handle_ = 0;
    std::uint32_t fb_ = 0;
    bool ok_ = false;
};

extern "C" void on_flip(int, unsigned int, unsigned int, unsigned int, void* pending) {
    *static_cast<bool*>(pending) = false;
}

bool check_display(const Options& opt) {
    const fpp::UniqueFd fd(open(opt.card.c_str(), O_RDWR | O_CLOEXEC));
    if (fd.get() < 0) {
        std::printf("vm-probe: FAIL display: cannot open %s: %s\n", opt.card.c_str(),
                    std::strerror(errno));
        return false;
    }
    const ResourcesPtr res(drmModeGetResources(fd.get()));
    if (!res) {
        std::printf("vm-probe: FAIL display: no KMS resources on %s\n", opt.card.c_str());
        return false;
    }
    std::printf("vm-probe: display %s: %d connectors, %d CRTCs\n", opt.card.c_str(),
                res->count_connectors, res->count_crtcs);
    for (int i = 0; i < res->count_connectors; ++i) {
        const ConnectorPtr c(drmModeGetConnector(fd.get(), res->connectors[i]));
        if (!c || c->connection != DRM_MODE_CONNECTED || c->count_modes == 0)
            continue;
        const drmModeModeInfo mode = c->modes[0];
        std::printf("vm-probe: connector %s-%u connected, mode %ux%u@%u\n",
                    drmModeGetConnectorTypeName(c->connector_type), c->connector_type_id,
                    mode.hdisplay, mode.vdisplay, mode.vrefresh);
        const EncoderPtr enc(drmModeGetEncoder(fd.get(), c->encoders[0]));
        if (!enc)
            break;
        std::uint32_t crtc = 0;
        for (int k = 0; k < res->count_crtcs; ++k)
            if ((enc->possible_crtcs & (1u << k)) != 0) {
                crtc = res->crtcs[k];
                break;
            }
        DumbFramebuffer dark(fd.get(), mode.hdisplay, mode.vdisplay, 0x20);
        DumbFramebuffer bright(fd.get(), mode.hdisplay, mode.vdisplay, 0xe0);
        if (crtc == 0 || !dark.ok() || !bright.ok())
            break;
        std::uint32_t connector_id = c->connector_id;
        drmModeModeInfo set_mode = mode;
        if (drmModeSetCrtc(fd.get(), crtc, dark.id(), 0, 0, &connector_id, 1, &set_mode) != 0) {
            std::printf("vm-probe: FAIL display: mode set: %s\n", std::strerror(errno));
            return false;
        }
        drmEventContext events{};
        events.version = 2;
        events.page_flip_handler = on_flip;
        const auto start = std::chrono::steady_clock::now();
        for (int f = 0; f < opt.flips; ++f) {
            bool pending = true;
            const std::uint32_t next = (f % 2 == 0) ? bright.id() : dark.id();
            if (drmModePageFlip(fd.get(), crtc, next, DRM_MODE_PAGE_FLIP_EVENT, &pending) != 0) {
                std::printf("vm-probe: FAIL display: page flip %d: %s\n", f, std::strerror(errno));
                return false;
            }
            while (pending) {
                pollfd p{fd.get(), POLLIN, 0};
                if (poll(&p, 1, 1000) <= 0) {
                    std::printf("vm-probe: FAIL display: no flip event within 1 s\n");
                    return false;
                }
                drmHandleEvent(fd.get(), &events);
            }
        }
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("vm-probe: display OK: %d page flips in %.3f s (%.0f per second)\n", opt.flips,
                    seconds, static_cast<double>(opt.flips) / seconds);
        return true;
    }
    std::printf("vm-probe: FAIL display: no connected connector could be lit\n");
    return false;
}

bool check_gpio(const Options& opt) {
    const ChipPtr chip(gpiod_chip_open_lookup(opt.chip.c_str()));
    if (!chip) {
        std::printf("vm-probe: FAIL gpio: cannot open %s: %s\n", opt.chip.c_str(),
                    std::strerror(errno));
        return false;
    }
    const unsigned int lines = gpiod_chip_num_lines(chip.get());
    std::printf("vm-probe: gpio %s [%s] (%u lines)\n", gpiod_chip_name(chip.get()),
                gpiod_chip_label(chip.get()), lines);
    for (unsigned int i = 0; i < lines; ++i) {
        gpiod_line* line = gpiod_chip_get_line(chip.get(), i);
        if (line == nullptr)
            continue;
        const char* consumer = gpiod_line_consumer(line);
        std::printf("vm-probe:   line %u: %s %s\n", i,
                    gpiod_line_direction(line) == GPIOD_LINE_DIRECTION_OUTPUT ? "output" : "input",
                    consumer != nullptr ? consumer : "unused");
    }
    const LinePtr output(gpiod_chip_get_line(chip.get(), opt.output));
    if (!output || gpiod_line_request_output(output.get(), "vm-probe", 0) != 0 ||
        gpiod_line_set_value(output.get(), 1) != 0 || gpiod_line_get_value(output.get()) != 1) {
        std::printf("vm-probe: FAIL gpio: cannot drive line %u: %s\n", opt.output,
                    std::strerror(errno));
        return false;
    }
    std::printf("vm-probe: gpio line %u driven high\n", opt.output);
    const LinePtr button(gpiod_chip_get_line(chip.get(), opt.button));
    if (!button || gpiod_line_request_rising_edge_events(button.get(), "vm-probe") != 0) {
        std::printf(
            "vm-probe: FAIL gpio: cannot request line %u for edges (held by gpio-keys?): %s\n",
            opt.button, std::strerror(errno));
        return false;
    }
    std::printf("vm-probe: waiting for the button on line %u\n", opt.button);
    std::fflush(stdout);
    const auto start = std::chrono::steady_clock::now();
    timespec timeout{};
    timeout.tv_sec = opt.wait_ms / 1000;
    timeout.tv_nsec = static_cast<long>(opt.wait_ms % 1000) * 1'000'000L;
    const int ready = gpiod_line_event_wait(button.get(), &timeout);
    gpiod_line_event event{};
    if (ready != 1 || gpiod_line_event_read(button.get(), &event) != 0) {
        std::printf("vm-probe: FAIL gpio: no button edge within %d ms\n", opt.wait_ms);
        return false;
    }
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("vm-probe: gpio OK: button %s edge after %.3f s\n",
                event.event_type == GPIOD_LINE_EVENT_RISING_EDGE ? "rising" : "falling", waited);
    return true;
}

bool parse_int(const char* text, int low, int high, int& out) {
    char* end = nullptr;
    errno = 0;
    const long v = std::strtol(text, &end, 10);
    if (errno != 0 || end == text || *end != '\0' || v < low || v > high)
        return false;
    out = static_cast<int>(v);
    return true;
}

} // namespace

int main(int argc, char** argv) {
    Options opt;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has_value = i + 1 < argc;
        int v = 0;
        if (a == "--card" && has_value)
            opt.card = argv[++i];
        else if (a == "--chip" && has_value)
            opt.chip = argv[++i];
        else if (a == "--button" && has_value && parse_int(argv[++i], 0, 1023, v))
            opt.button = static_cast<unsigned int>(v);
        else if (a == "--output" && has_value && parse_int(argv[++i], 0, 1023, v))
            opt.output = static_cast<unsigned int>(v);
        else if (a == "--flips" && has_value && parse_int(argv[++i], 1, 100'000, v))
            opt.flips = v;
        else if (a == "--wait-ms" && has_value && parse_int(argv[++i], 1, 3'600'000, v))
            opt.wait_ms = v;
        else {
            std::fprintf(stderr,
                         "usage: vm-probe [--card PATH] [--chip NAME] [--button N] [--output N] "
                         "[--flips N] [--wait-ms N]\n");
            return 2;
        }
    }
    const bool display_ok = check_display(opt);
    const bool gpio_ok = check_gpio(opt);
    std::printf("vm-probe: %s\n", display_ok && gpio_ok ? "all checks passed" : "FAILED");
    return display_ok && gpio_ok ? 0 : 1;
}
