// vm-probe: checks, inside the virtual ARM board, that the scanner's device
// libraries load and reach the kernel devices the scanner uses:
//   1. GPIO (libgpiod 1.x, or 2.x when built with FPP_PROBE_LIBGPIOD2): the
//      chip's lines are listed and an output line (the trigger) is requested;
//   2. DRM/KMS (libdrm): the first connected connector of /dev/dri/card0 is
//      lit with a dumb buffer, then page flips are timed, the trigger line
//      pulsed on each flip event as the scanner does: the time from the
//      flip's kernel timestamp to the line set high is the board's
//      flip-to-trigger latency, and the set call's own time the library's;
//   3. the button line is waited on for a rising edge (the harness presses
//      the button when it reads "vm-probe: waiting for the button" on the
//      console), and the edge read after its kernel timestamp is timed.
// Built by tests/vm/run_vm_probe.sh with the cross compiler; not part of the
// CMake build (of the project it uses only the header-only fpp::UniqueFd).
// Usage: vm-probe [--card PATH] [--chip NAME] [--button N] [--output N]
//                 [--flips N] [--wait-ms N]
// Exit status: 0 when every check passed, 1 otherwise.
#include <fpp/unique_fd.hpp>

#include <gpiod.h>
#include <xf86drm.h>
#include <xf86drmMode.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fcntl.h>
#include <memory>
#include <poll.h>
#include <string>
#include <sys/mman.h>
#include <unistd.h>
#include <vector>

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
std::int64_t now_ns() {
    timespec t{};
    clock_gettime(CLOCK_MONOTONIC, &t);
    return std::int64_t(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

#if FPP_PROBE_LIBGPIOD2
// The probe's GPIO calls over libgpiod 2.x: requests made from settings and
// configs, each handle owned by a unique_ptr freeing it.
using ChipPtr = std::unique_ptr<gpiod_chip, Deleter<gpiod_chip, gpiod_chip_close>>;
using ChipInfoPtr =
    std::unique_ptr<gpiod_chip_info, Deleter<gpiod_chip_info, gpiod_chip_info_free>>;
using LineInfoPtr =
    std::unique_ptr<gpiod_line_info, Deleter<gpiod_line_info, gpiod_line_info_free>>;
using SettingsPtr =
    std::unique_ptr<gpiod_line_settings, Deleter<gpiod_line_settings, gpiod_line_settings_free>>;
using LineConfigPtr =
    std::unique_ptr<gpiod_line_config, Deleter<gpiod_line_config, gpiod_line_config_free>>;
using RequestConfigPtr =
    std::unique_ptr<gpiod_request_config, Deleter<gpiod_request_config, gpiod_request_config_free>>;
using RequestPtr =
    std::unique_ptr<gpiod_line_request, Deleter<gpiod_line_request, gpiod_line_request_release>>;
using EventBufferPtr =
    std::unique_ptr<gpiod_edge_event_buffer,
                    Deleter<gpiod_edge_event_buffer, gpiod_edge_event_buffer_free>>;

class Gpio {
public:
    static const char* version() { return gpiod_api_version(); }
    bool open(const std::string& name) {
        const std::string path = name.find('/') == std::string::npos ? "/dev/" + name : name;
        chip_.reset(gpiod_chip_open(path.c_str()));
        return static_cast<bool>(chip_);
    }
    void list() const {
        const ChipInfoPtr info(gpiod_chip_get_info(chip_.get()));
        if (!info)
            return;
        const auto lines = static_cast<unsigned int>(gpiod_chip_info_get_num_lines(info.get()));
        std::printf("vm-probe: gpio %s [%s] (%u lines)\n", gpiod_chip_info_get_name(info.get()),
                    gpiod_chip_info_get_label(info.get()), lines);
        for (unsigned int i = 0; i < lines; ++i) {
            const LineInfoPtr line(gpiod_chip_get_line_info(chip_.get(), i));
            if (!line)
                continue;
            const char* consumer = gpiod_line_info_get_consumer(line.get());
            std::printf("vm-probe:   line %u: %s %s\n", i,
                        gpiod_line_info_get_direction(line.get()) == GPIOD_LINE_DIRECTION_OUTPUT
                            ? "output"
                            : "input",
                        consumer != nullptr ? consumer : "unused");
        }
    }
    bool request_output(unsigned int offset) {
        output_ = request(offset, true);
        output_offset_ = offset;
        return static_cast<bool>(output_);
    }
    bool set(int value) {
        return gpiod_line_request_set_value(output_.get(), output_offset_,
                                            value != 0 ? GPIOD_LINE_VALUE_ACTIVE
                                                       : GPIOD_LINE_VALUE_INACTIVE) == 0;
    }
    int get() { return gpiod_line_request_get_value(output_.get(), output_offset_); }
    bool request_button(unsigned int offset) {
        button_ = request(offset, false);
        events_.reset(gpiod_edge_event_buffer_new(1));
        return button_ && events_;
    }
    // 1: an edge read (its kind and kernel time), 0: none within wait_ms, -1: error.
    int wait_edge(int wait_ms, bool& rising, std::int64_t& timestamp_ns) {
        const int ready =
            gpiod_line_request_wait_edge_events(button_.get(), std::int64_t(wait_ms) * 1'000'000);
        if (ready != 1)
            return ready;
        if (gpiod_line_request_read_edge_events(button_.get(), events_.get(), 1) != 1)
            return -1;
        gpiod_edge_event* event = gpiod_edge_event_buffer_get_event(events_.get(), 0);
        rising = gpiod_edge_event_get_event_type(event) == GPIOD_EDGE_EVENT_RISING_EDGE;
        timestamp_ns = static_cast<std::int64_t>(gpiod_edge_event_get_timestamp_ns(event));
        return 1;
    }

private:
    RequestPtr request(unsigned int offset, bool output) const {
        const SettingsPtr settings(gpiod_line_settings_new());
        const LineConfigPtr line_config(gpiod_line_config_new());
        const RequestConfigPtr request_config(gpiod_request_config_new());
        if (!settings || !line_config || !request_config)
            return nullptr;
        if (output) {
            gpiod_line_settings_set_direction(settings.get(), GPIOD_LINE_DIRECTION_OUTPUT);
            gpiod_line_settings_set_output_value(settings.get(), GPIOD_LINE_VALUE_INACTIVE);
        } else {
            gpiod_line_settings_set_direction(settings.get(), GPIOD_LINE_DIRECTION_INPUT);
            gpiod_line_settings_set_edge_detection(settings.get(), GPIOD_LINE_EDGE_RISING);
        }
        if (gpiod_line_config_add_line_settings(line_config.get(), &offset, 1, settings.get()) != 0)
            return nullptr;
        gpiod_request_config_set_consumer(request_config.get(), "vm-probe");
        return RequestPtr(
            gpiod_chip_request_lines(chip_.get(), request_config.get(), line_config.get()));
    }

    ChipPtr chip_;
    RequestPtr output_;
    unsigned int output_offset_ = 0;
    RequestPtr button_;
    EventBufferPtr events_;
};
#else
// The probe's GPIO calls over libgpiod 1.x: the line objects belong to the
// chip, each request is released by a unique_ptr.
using ChipPtr = std::unique_ptr<gpiod_chip, Deleter<gpiod_chip, gpiod_chip_close>>;
using LinePtr = std::unique_ptr<gpiod_line, Deleter<gpiod_line, gpiod_line_release>>;

class Gpio {
public:
    static const char* version() { return gpiod_version_string(); }
    bool open(const std::string& name) {
        chip_.reset(gpiod_chip_open_lookup(name.c_str()));
        return static_cast<bool>(chip_);
    }
    void list() const {
        const unsigned int lines = gpiod_chip_num_lines(chip_.get());
        std::printf("vm-probe: gpio %s [%s] (%u lines)\n", gpiod_chip_name(chip_.get()),
                    gpiod_chip_label(chip_.get()), lines);
        for (unsigned int i = 0; i < lines; ++i) {
            gpiod_line* line = gpiod_chip_get_line(chip_.get(), i);
            if (line == nullptr)
                continue;
            const char* consumer = gpiod_line_consumer(line);
            std::printf("vm-probe:   line %u: %s %s\n", i,
                        gpiod_line_direction(line) == GPIOD_LINE_DIRECTION_OUTPUT ? "output"
                                                                                  : "input",
                        consumer != nullptr ? consumer : "unused");
        }
    }
    bool request_output(unsigned int offset) {
        output_.reset(gpiod_chip_get_line(chip_.get(), offset));
        return output_ && gpiod_line_request_output(output_.get(), "vm-probe", 0) == 0;
    }
    bool set(int value) { return gpiod_line_set_value(output_.get(), value) == 0; }
    int get() { return gpiod_line_get_value(output_.get()); }
    bool request_button(unsigned int offset) {
        button_.reset(gpiod_chip_get_line(chip_.get(), offset));
        return button_ && gpiod_line_request_rising_edge_events(button_.get(), "vm-probe") == 0;
    }
    // 1: an edge read (its kind and kernel time), 0: none within wait_ms, -1: error.
    int wait_edge(int wait_ms, bool& rising, std::int64_t& timestamp_ns) {
        timespec timeout{};
        timeout.tv_sec = wait_ms / 1000;
        timeout.tv_nsec = static_cast<long>(wait_ms % 1000) * 1'000'000L;
        const int ready = gpiod_line_event_wait(button_.get(), &timeout);
        if (ready != 1)
            return ready;
        gpiod_line_event event{};
        if (gpiod_line_event_read(button_.get(), &event) != 0)
            return -1;
        rising = event.event_type == GPIOD_LINE_EVENT_RISING_EDGE;
        timestamp_ns = std::int64_t(event.ts.tv_sec) * 1'000'000'000 + event.ts.tv_nsec;
        return 1;
    }

private:
    ChipPtr chip_;
    LinePtr output_;
    LinePtr button_;
};
#endif

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

// A page flip waited for, and its kernel timestamp (CLOCK_MONOTONIC).
struct PendingFlip {
    bool pending = true;
    std::int64_t timestamp_ns = 0;
};

extern "C" void on_flip(int, unsigned int, unsigned int sec, unsigned int usec, void* data) {
    auto* flip = static_cast<PendingFlip*>(data);
    flip->pending = false;
    flip->timestamp_ns = std::int64_t(sec) * 1'000'000'000 + std::int64_t(usec) * 1000;
}

double percentile_us(std::vector<std::int64_t> ns, double p) {
    if (ns.empty())
        return 0.0;
    const auto k = static_cast<std::size_t>(p * static_cast<double>(ns.size() - 1) + 0.5);
    std::nth_element(ns.begin(), ns.begin() + static_cast<std::ptrdiff_t>(k), ns.end());
    return static_cast<double>(ns[k]) / 1000.0;
}

// With `trigger`, its line is pulsed on each flip event.
bool check_display(const Options& opt, Gpio* trigger) {
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
        std::vector<std::int64_t> to_trigger; // flip's timestamp to the line set high
        std::vector<std::int64_t> set_call;   // the set call alone
        const auto start = std::chrono::steady_clock::now();
        for (int f = 0; f < opt.flips; ++f) {
            PendingFlip flip;
            const std::uint32_t next = (f % 2 == 0) ? bright.id() : dark.id();
            if (drmModePageFlip(fd.get(), crtc, next, DRM_MODE_PAGE_FLIP_EVENT, &flip) != 0) {
                std::printf("vm-probe: FAIL display: page flip %d: %s\n", f, std::strerror(errno));
                return false;
            }
            while (flip.pending) {
                pollfd p{fd.get(), POLLIN, 0};
                if (poll(&p, 1, 1000) <= 0) {
                    std::printf("vm-probe: FAIL display: no flip event within 1 s\n");
                    return false;
                }
                drmHandleEvent(fd.get(), &events);
            }
            if (trigger == nullptr)
                continue;
            const std::int64_t before = now_ns();
            const bool high = trigger->set(1);
            const std::int64_t after = now_ns();
            if (!high || !trigger->set(0)) {
                std::printf("vm-probe: FAIL trigger: cannot pulse line %u: %s\n", opt.output,
                            std::strerror(errno));
                return false;
            }
            to_trigger.push_back(after - flip.timestamp_ns);
            set_call.push_back(after - before);
        }
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("vm-probe: display OK: %d page flips in %.3f s (%.0f per second)\n", opt.flips,
                    seconds, static_cast<double>(opt.flips) / seconds);
        if (trigger != nullptr)
            std::printf(
                "vm-probe: trigger OK: %zu pulses; flip to trigger line high: median %.0f us,"
                " 95th percentile %.0f us, max %.0f us; set call: median %.1f us, max %.1f"
                " us\n",
                to_trigger.size(), percentile_us(to_trigger, 0.5), percentile_us(to_trigger, 0.95),
                percentile_us(to_trigger, 1.0), percentile_us(set_call, 0.5),
                percentile_us(set_call, 1.0));
        return true;
    }
    std::printf("vm-probe: FAIL display: no connected connector could be lit\n");
    return false;
}

// Opens the chip, lists its lines and requests the trigger line, drives it
// high and reads it back, then leaves it low.
bool open_gpio(const Options& opt, Gpio& gpio) {
    std::printf("vm-probe: libgpiod %s\n", Gpio::version());
    if (!gpio.open(opt.chip)) {
        std::printf("vm-probe: FAIL gpio: cannot open %s: %s\n", opt.chip.c_str(),
                    std::strerror(errno));
        return false;
    }
    gpio.list();
    if (!gpio.request_output(opt.output) || !gpio.set(1) || gpio.get() != 1 || !gpio.set(0)) {
        std::printf("vm-probe: FAIL gpio: cannot drive line %u: %s\n", opt.output,
                    std::strerror(errno));
        return false;
    }
    std::printf("vm-probe: gpio line %u driven high\n", opt.output);
    return true;
}

bool check_button(const Options& opt, Gpio& gpio) {
    if (!gpio.request_button(opt.button)) {
        std::printf(
            "vm-probe: FAIL gpio: cannot request line %u for edges (held by gpio-keys?): %s\n",
            opt.button, std::strerror(errno));
        return false;
    }
    std::printf("vm-probe: waiting for the button on line %u\n", opt.button);
    std::fflush(stdout);
    const auto start = std::chrono::steady_clock::now();
    bool rising = false;
    std::int64_t edge_ns = 0;
    if (gpio.wait_edge(opt.wait_ms, rising, edge_ns) != 1) {
        std::printf("vm-probe: FAIL gpio: no button edge within %d ms\n", opt.wait_ms);
        return false;
    }
    const std::int64_t read_ns = now_ns();
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("vm-probe: gpio OK: button %s edge after %.3f s, read %.0f us after its"
                " kernel timestamp\n",
                rising ? "rising" : "falling", waited,
                static_cast<double>(read_ns - edge_ns) / 1000.0);
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
    Gpio gpio;
    const bool gpio_ok = open_gpio(opt, gpio);
    const bool display_ok = check_display(opt, gpio_ok ? &gpio : nullptr);
    const bool button_ok = gpio_ok && check_button(opt, gpio);
    const bool ok = display_ok && gpio_ok && button_ok;
    std::printf("vm-probe: %s\n", ok ? "all checks passed" : "FAILED");
    return ok ? 0 : 1;
}
