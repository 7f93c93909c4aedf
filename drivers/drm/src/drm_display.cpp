// DRM/KMS display. Every kernel object has an RAII owner: the card fd
// (UniqueFd), dumb buffers, framebuffers, mappings, the mode blob and every
// libdrm allocation (unique_ptr with the matching drmModeFree* deleter).
#include <fpp/drivers/drm_display.hpp>

#include <fpp/drivers/device_error.hpp>
#include <fpp/unique_fd.hpp>

#include <drm_fourcc.h>
#include <xf86drm.h>
#include <xf86drmMode.h>

#include <fcntl.h>
#include <poll.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <optional>
#include <stdexcept>

namespace fpp::drivers {
namespace {

template <class T, void (*Free)(T*)> struct DrmFree {
    void operator()(T* p) const noexcept {
        if (p != nullptr)
            Free(p);
    }
};
using ResourcesPtr = std::unique_ptr<drmModeRes, DrmFree<drmModeRes, drmModeFreeResources>>;
using ConnectorPtr =
    std::unique_ptr<drmModeConnector, DrmFree<drmModeConnector, drmModeFreeConnector>>;
using EncoderPtr = std::unique_ptr<drmModeEncoder, DrmFree<drmModeEncoder, drmModeFreeEncoder>>;
using CrtcPtr = std::unique_ptr<drmModeCrtc, DrmFree<drmModeCrtc, drmModeFreeCrtc>>;
using PlaneResPtr =
    std::unique_ptr<drmModePlaneRes, DrmFree<drmModePlaneRes, drmModeFreePlaneResources>>;
using PlanePtr = std::unique_ptr<drmModePlane, DrmFree<drmModePlane, drmModeFreePlane>>;
using PropertiesPtr =
    std::unique_ptr<drmModeObjectProperties,
                    DrmFree<drmModeObjectProperties, drmModeFreeObjectProperties>>;
using PropertyPtr =
    std::unique_ptr<drmModePropertyRes, DrmFree<drmModePropertyRes, drmModeFreeProperty>>;
using AtomicReqPtr =
    std::unique_ptr<drmModeAtomicReq, DrmFree<drmModeAtomicReq, drmModeAtomicFree>>;

std::string errno_text(int error) {
    return std::strerror(error);
}

// A dumb buffer, its framebuffer and its CPU mapping; released in reverse.
class ScanoutBuffer {
public:
    ScanoutBuffer(int fd, Size size, const std::string& device) : fd_(fd) {
        drm_mode_create_dumb create{};
        create.width = static_cast<std::uint32_t>(size.width);
        create.height = static_cast<std::uint32_t>(size.height);
        create.bpp = 32;
        if (drmIoctl(fd, DRM_IOCTL_MODE_CREATE_DUMB, &create) != 0)
            throw DeviceError(DeviceKind::display, device,
                              "cannot create a dumb buffer: " + errno_text(errno));
        handle_ = create.handle;
        pitch_ = create.pitch;
        bytes_ = create.size;
        const std::uint32_t handles[4] = {handle_, 0, 0, 0};
        const std::uint32_t pitches[4] = {pitch_, 0, 0, 0};
        const std::uint32_t offsets[4] = {0, 0, 0, 0};
        if (drmModeAddFB2(fd, create.width, create.height, DRM_FORMAT_XRGB8888, handles, pitches,
                          offsets, &fb_id_, 0) != 0) {
            const int error = errno;
            destroy_dumb();
            throw DeviceError(DeviceKind::display, device,
                              "cannot add a framebuffer: " + errno_text(error));
        }
        drm_mode_map_dumb map{};
        map.handle = handle_;
        void* pixels = MAP_FAILED;
        if (drmIoctl(fd, DRM_IOCTL_MODE_MAP_DUMB, &map) == 0)
            pixels = mmap(nullptr, bytes_, PROT_READ | PROT_WRITE, MAP_SHARED, fd,
                          static_cast<off_t>(map.offset));
        if (pixels == MAP_FAILED) {
            const int error = errno;
            drmModeRmFB(fd, fb_id_);
            destroy_dumb();
            throw DeviceError(DeviceKind::display, device,
                              "cannot map a dumb buffer: " + errno_text(error));
        }
        pixels_ = static_cast<std::uint8_t*>(pixels);
    }
    ~ScanoutBuffer() {
        munmap(pixels_, bytes_);
        drmModeRmFB(fd_, fb_id_);
        destroy_dumb();
    }
    ScanoutBuffer(const ScanoutBuffer&) = delete;
    ScanoutBuffer& operator=(const ScanoutBuffer&) = delete;

    std::uint32_t fb_id() const { return fb_id_; }

    // Grey level in B, G and R; X left 0.
    void draw(const Image<std::uint8_t>& pattern) {
        for (int y = 0; y < pattern.height(); ++y) {
            const std::uint8_t* in = pattern.row(y);
            std::uint8_t* out = pixels_ + std::size_t(y) * pitch_;
            for (int x = 0; x < pattern.width(); ++x) {
                const std::uint8_t v = in[x];
                out[4 * x] = v;
                out[4 * x + 1] = v;
                out[4 * x + 2] = v;
                out[4 * x + 3] = 0;
            }
        }
    }

private:
    void destroy_dumb() {
        drm_mode_destroy_dumb destroy{};
        destroy.handle = handle_;
        drmIoctl(fd_, DRM_IOCTL_MODE_DESTROY_DUMB, &destroy);
    }
    int fd_;
    std::uint32_t handle_ = 0;
    std::uint32_t pitch_ = 0;
    std::uint64_t bytes_ = 0;
    std::uint32_t fb_id_ = 0;
    std::uint8_t* pixels_ = nullptr;
};

// A property blob (the mode), destroyed with its owner.
class PropertyBlob {
public:
    PropertyBlob(int fd, const void* data, std::size_t size, const std::string& device) : fd_(fd) {
        if (drmModeCreatePropertyBlob(fd, data, size, &id_) != 0)
            throw DeviceError(DeviceKind::display, device,
                              "cannot create the mode blob: " + errno_text(errno));
    }
    ~PropertyBlob() { drmModeDestroyPropertyBlob(fd_, id_); }
    PropertyBlob(const PropertyBlob&) = delete;
    PropertyBlob& operator=(const PropertyBlob&) = delete;
    std::uint32_t id() const { return id_; }

private:
    int fd_;
    std::uint32_t id_ = 0;
};

std::uint32_t property_id(int fd, std::uint32_t object, std::uint32_t type, const char* name,
                          const std::string& device) {
    const PropertiesPtr props(drmModeObjectGetProperties(fd, object, type));
    if (props)
        for (std::uint32_t i = 0; i < props->count_props; ++i) {
            const PropertyPtr prop(drmModeGetProperty(fd, props->props[i]));
            if (prop && std::strcmp(prop->name, name) == 0)
                return prop->prop_id;
        }
    throw DeviceError(DeviceKind::display, device,
                      std::string("object ") + std::to_string(object) + " has no property " + name);
}

std::optional<std::uint64_t> property_value(int fd, std::uint32_t object, std::uint32_t type,
                                            const char* name) {
    const PropertiesPtr props(drmModeObjectGetProperties(fd, object, type));
    if (props)
        for (std::uint32_t i = 0; i < props->count_props; ++i) {
            const PropertyPtr prop(drmModeGetProperty(fd, props->props[i]));
            if (prop && std::strcmp(prop->name, name) == 0)
                return props->prop_values[i];
        }
    return std::nullopt;
}

std::string connector_name(const drmModeConnector& c) {
    const char* type = drmModeGetConnectorTypeName(c.connector_type);
    return std::string(type != nullptr ? type : "Unknown") + "-" +
           std::to_string(c.connector_type_id);
}

double refresh_hz(const drmModeModeInfo& mode) {
    if (mode.htotal == 0 || mode.vtotal == 0)
        return double(mode.vrefresh);
    return double(mode.clock) * 1000.0 / (double(mode.htotal) * double(mode.vtotal));
}

std::int64_t to_ns(unsigned int sec, unsigned int usec) {
    return std::int64_t(sec) * 1'000'000'000 + std::int64_t(usec) * 1000;
}

} // namespace

struct DrmDisplay::Impl {
    std::string name;
    UniqueFd fd;
    bool atomic = false;
    std::uint32_t connector_id = 0;
    std::uint32_t crtc_id = 0;
    std::uint32_t plane_id = 0;
    drmModeModeInfo mode{};
    CrtcPtr saved_crtc; // configuration found at open, put back by restore()
    std::vector<std::unique_ptr<ScanoutBuffer>> buffers;
    std::unique_ptr<PropertyBlob> mode_blob;
    bool mode_set = false;
    bool restored = false;
    std::optional<std::size_t> pending; // index of the flip in flight
    std::optional<FlipEvent> completed; // set by the event handler
    std::vector<FlipEvent> log;

    struct AtomicIds {
        std::uint32_t connector_crtc_id = 0, crtc_mode_id = 0, crtc_active = 0;
        std::uint32_t plane_fb_id = 0, plane_crtc_id = 0, src_x = 0, src_y = 0, src_w = 0,
                      src_h = 0, crtc_x = 0, crtc_y = 0, crtc_w = 0, crtc_h = 0;
    } ids;

    static void on_flip(int, unsigned int sequence, unsigned int sec, unsigned int usec,
                        unsigned int /*crtc_id*/, void* user_data) {
        auto* self = static_cast<Impl*>(user_data);
        if (!self->pending)
            return;
        FlipEvent event;
        event.index = *self->pending;
        event.sequence = sequence;
        event.timestamp_ns = to_ns(sec, usec); // CLOCK_MONOTONIC (DRM_CAP_TIMESTAMP_MONOTONIC)
        self->completed = event;
    }

    void open_card(const std::string& path) {
        name = "display " + path;
        fd.reset(open(path.c_str(), O_RDWR | O_CLOEXEC));
        if (!fd.valid())
            throw DeviceError(DeviceKind::display, name, "cannot open: " + errno_text(errno));
    }

    void pick_output(const DrmDisplaySettings& settings) {
        const int f = fd.get();
        const ResourcesPtr res(drmModeGetResources(f));
        if (!res)
            throw DeviceError(DeviceKind::display, name, "not a KMS device: " + errno_text(errno));

        std::vector<ConnectorPtr> connectors;
        std::vector<DrmConnectorInfo> infos;
        for (int i = 0; i < res->count_connectors; ++i) {
            ConnectorPtr c(drmModeGetConnector(f, res->connectors[i]));
            if (!c)
                continue;
            DrmConnectorInfo info;
            info.name = connector_name(*c);
            info.connected = c->connection == DRM_MODE_CONNECTED;
            for (int m = 0; m < c->count_modes; ++m)
                info.modes.push_back({c->modes[m].hdisplay, c->modes[m].vdisplay,
                                      refresh_hz(c->modes[m]),
                                      (c->modes[m].type & DRM_MODE_TYPE_PREFERRED) != 0});
            infos.push_back(std::move(info));
            connectors.push_back(std::move(c));
        }
        const DrmOutputChoice choice = choose_drm_output(infos, settings.output, name);
        const drmModeConnector& connector = *connectors[choice.connector];
        connector_id = connector.connector_id;
        mode = connector.modes[choice.mode];

        // The CRTC driving the connector now, else the first its encoders allow.
        std::optional<int> crtc_index;
        for (int e = 0; e < connector.count_encoders && !crtc_index; ++e) {
            const EncoderPtr encoder(drmModeGetEncoder(f, connector.encoders[e]));
            if (!encoder)
                continue;
            if (encoder->encoder_id == connector.encoder_id && encoder->crtc_id != 0) {
                for (int c = 0; c < res->count_crtcs; ++c)
                    if (res->crtcs[c] == encoder->crtc_id)
                        crtc_index = c;
            }
            for (int c = 0; c < res->count_crtcs && !crtc_index; ++c)
                if (encoder->possible_crtcs & (1u << c))
                    crtc_index = c;
        }
        if (!crtc_index)
            throw DeviceError(DeviceKind::display, name,
                              "no CRTC can drive " + infos[choice.connector].name);
        crtc_id = res->crtcs[*crtc_index];
        saved_crtc.reset(drmModeGetCrtc(f, crtc_id));

        if (atomic)
            find_primary_plane(*crtc_index);
    }

    void find_primary_plane(int crtc_index) {
        const int f = fd.get();
        const PlaneResPtr planes(drmModeGetPlaneResources(f));
        for (std::uint32_t i = 0; planes && i < planes->count_planes && plane_id == 0; ++i) {
            const PlanePtr plane(drmModeGetPlane(f, planes->planes[i]));
            if (!plane || !(plane->possible_crtcs & (1u << crtc_index)))
                continue;
            if (property_value(f, plane->plane_id, DRM_MODE_OBJECT_PLANE, "type") ==
                std::optional<std::uint64_t>(DRM_PLANE_TYPE_PRIMARY))
                plane_id = plane->plane_id;
        }
        if (plane_id == 0) {
            atomic = false; // no primary plane found: fall back to the legacy API
            return;
        }
        ids.connector_crtc_id =
            property_id(f, connector_id, DRM_MODE_OBJECT_CONNECTOR, "CRTC_ID", name);
        ids.crtc_mode_id = property_id(f, crtc_id, DRM_MODE_OBJECT_CRTC, "MODE_ID", name);
        ids.crtc_active = property_id(f, crtc_id, DRM_MODE_OBJECT_CRTC, "ACTIVE", name);
        const auto plane_prop = [&](const char* prop) {
            return property_id(f, plane_id, DRM_MODE_OBJECT_PLANE, prop, name);
        };
        ids.plane_fb_id = plane_prop("FB_ID");
        ids.plane_crtc_id = plane_prop("CRTC_ID");
        ids.src_x = plane_prop("SRC_X");
        ids.src_y = plane_prop("SRC_Y");
        ids.src_w = plane_prop("SRC_W");
        ids.src_h = plane_prop("SRC_H");
        ids.crtc_x = plane_prop("CRTC_X");
        ids.crtc_y = plane_prop("CRTC_Y");
        ids.crtc_w = plane_prop("CRTC_W");
        ids.crtc_h = plane_prop("CRTC_H");
    }

    void atomic_modeset(std::size_t index) {
        const int f = fd.get();
        mode_blob = std::make_unique<PropertyBlob>(f, &mode, sizeof mode, name);
        const AtomicReqPtr req(drmModeAtomicAlloc());
        if (!req)
            throw std::bad_alloc();
        drmModeAtomicReq* r = req.get();
        drmModeAtomicAddProperty(r, connector_id, ids.connector_crtc_id, crtc_id);
        drmModeAtomicAddProperty(r, crtc_id, ids.crtc_mode_id, mode_blob->id());
        drmModeAtomicAddProperty(r, crtc_id, ids.crtc_active, 1);
        drmModeAtomicAddProperty(r, plane_id, ids.plane_fb_id, buffers[index]->fb_id());
        drmModeAtomicAddProperty(r, plane_id, ids.plane_crtc_id, crtc_id);
        const std::uint64_t w = mode.hdisplay, h = mode.vdisplay;
        drmModeAtomicAddProperty(r, plane_id, ids.src_x, 0);
        drmModeAtomicAddProperty(r, plane_id, ids.src_y, 0);
        drmModeAtomicAddProperty(r, plane_id, ids.src_w, w << 16); // 16.16 fixed point
        drmModeAtomicAddProperty(r, plane_id, ids.src_h, h << 16);
        drmModeAtomicAddProperty(r, plane_id, ids.crtc_x, 0);
        drmModeAtomicAddProperty(r, plane_id, ids.crtc_y, 0);
        drmModeAtomicAddProperty(r, plane_id, ids.crtc_w, w);
        drmModeAtomicAddProperty(r, plane_id, ids.crtc_h, h);
        if (drmModeAtomicCommit(f, r, DRM_MODE_ATOMIC_TEST_ONLY | DRM_MODE_ATOMIC_ALLOW_MODESET,
                                nullptr) != 0)
            throw DeviceError(DeviceKind::display, name,
                              "the card rejects the modeset (test commit): " + errno_text(errno));
        if (drmModeAtomicCommit(f, r, DRM_MODE_ATOMIC_ALLOW_MODESET | DRM_MODE_PAGE_FLIP_EVENT,
                                this) != 0)
            throw DeviceError(DeviceKind::display, name, "modeset failed: " + errno_text(errno));
    }

    void legacy_modeset(std::size_t index) {
        const int f = fd.get();
        if (drmModeSetCrtc(f, crtc_id, buffers[index]->fb_id(), 0, 0, &connector_id, 1, &mode) != 0)
            throw DeviceError(DeviceKind::display, name, "modeset failed: " + errno_text(errno));
        // A flip to the same buffer gives the event that marks it on screen.
        if (drmModePageFlip(f, crtc_id, buffers[index]->fb_id(), DRM_MODE_PAGE_FLIP_EVENT, this) !=
            0)
            throw DeviceError(DeviceKind::display, name, "page flip failed: " + errno_text(errno));
    }

    void flip(std::size_t index) {
        const int f = fd.get();
        if (atomic) {
            const AtomicReqPtr req(drmModeAtomicAlloc());
            if (!req)
                throw std::bad_alloc();
            drmModeAtomicAddProperty(req.get(), plane_id, ids.plane_fb_id, buffers[index]->fb_id());
            if (drmModeAtomicCommit(f, req.get(),
                                    DRM_MODE_ATOMIC_NONBLOCK | DRM_MODE_PAGE_FLIP_EVENT, this) != 0)
                throw DeviceError(DeviceKind::display, name,
                                  "page flip to pattern " + std::to_string(index) +
                                      " failed: " + errno_text(errno));
        } else if (drmModePageFlip(f, crtc_id, buffers[index]->fb_id(), DRM_MODE_PAGE_FLIP_EVENT,
                                   this) != 0) {
            throw DeviceError(DeviceKind::display, name,
                              "page flip to pattern " + std::to_string(index) +
                                  " failed: " + errno_text(errno));
        }
    }
};

DrmDisplay::DrmDisplay(const DrmDisplaySettings& settings) : impl_(std::make_unique<Impl>()) {
    Impl& d = *impl_;
    std::vector<std::string> candidates;
    if (settings.card == "auto") {
        for (int i = 0; i < 16; ++i) {
            const std::string path = "/dev/dri/card" + std::to_string(i);
            if (std::filesystem::exists(path))
                candidates.push_back(path);
        }
        if (candidates.empty())
            throw DeviceError(DeviceKind::display, "display auto", "no DRM card in /dev/dri");
    } else {
        candidates.push_back(settings.card);
    }
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        try {
            d.open_card(candidates[i]);
            d.atomic = settings.allow_atomic &&
                       drmSetClientCap(d.fd.get(), DRM_CLIENT_CAP_UNIVERSAL_PLANES, 1) == 0 &&
                       drmSetClientCap(d.fd.get(), DRM_CLIENT_CAP_ATOMIC, 1) == 0;
            d.pick_output(settings);
            return;
        } catch (const DeviceError&) {
            d.fd.reset();
            if (i + 1 == candidates.size())
                throw; // the last card's reason
        }
    }
}

DrmDisplay::~DrmDisplay() {
    try {
        restore();
    } catch (...) {
        // Nothing more can be done for the console while closing.
    }
}

Size DrmDisplay::size() const {
    return {impl_->mode.hdisplay, impl_->mode.vdisplay};
}
bool DrmDisplay::atomic() const {
    return impl_->atomic;
}
const std::string& DrmDisplay::name() const {
    return impl_->name;
}
const std::vector<FlipEvent>& DrmDisplay::flip_log() const {
    return impl_->log;
}

void DrmDisplay::prepare(const std::vector<Image<std::uint8_t>>& patterns) {
    Impl& d = *impl_;
    if (d.pending)
        throw DeviceError(DeviceKind::display, d.name, "prepare() while a flip is pending");
    for (std::size_t i = 0; i < patterns.size(); ++i)
        if (patterns[i].size() != size() || patterns[i].channels() != 1)
            throw std::invalid_argument("pattern " + std::to_string(i) +
                                        " is not single-channel at the display size");
    // Buffers on screen stay until the new ones are shown.
    std::vector<std::unique_ptr<ScanoutBuffer>> buffers;
    for (const auto& pattern : patterns) {
        buffers.push_back(std::make_unique<ScanoutBuffer>(d.fd.get(), size(), d.name));
        buffers.back()->draw(pattern);
    }
    std::swap(d.buffers, buffers);
    if (d.mode_set && !buffers.empty()) {
        // The old buffer on screen would vanish with its framebuffer (the CRTC
        // turns off): put the first new one up first.
        show(0);
        (void)wait_flip(std::chrono::milliseconds(1000));
    }
}

void DrmDisplay::show(std::size_t index) {
    Impl& d = *impl_;
    if (index >= d.buffers.size())
        throw DeviceError(DeviceKind::display, d.name,
                          "pattern " + std::to_string(index) + " not prepared (" +
                              std::to_string(d.buffers.size()) + " are)");
    if (d.pending)
        throw DeviceError(DeviceKind::display, d.name,
                          "flip to pattern " + std::to_string(index) +
                              " while the flip to pattern " + std::to_string(*d.pending) +
                              " is pending");
    d.completed.reset();
    d.pending = index;
    try {
        if (!d.mode_set) {
            if (d.atomic)
                d.atomic_modeset(index);
            else
                d.legacy_modeset(index);
            d.mode_set = true;
            d.restored = false;
        } else {
            d.flip(index);
        }
    } catch (...) {
        d.pending.reset();
        throw;
    }
}

FlipEvent DrmDisplay::wait_flip(std::chrono::milliseconds timeout) {
    Impl& d = *impl_;
    if (!d.pending)
        throw DeviceError(DeviceKind::display, d.name, "wait_flip() with no flip pending");
    drmEventContext context{};
    context.version = 3; // page_flip_handler2: also gets the CRTC
    context.page_flip_handler2 = &Impl::on_flip;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!d.completed) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        if (left.count() < 0)
            throw DeviceError(DeviceKind::display, d.name,
                              "flip to pattern " + std::to_string(*d.pending) +
                                  " not completed within " + std::to_string(timeout.count()) +
                                  " ms");
        pollfd p{d.fd.get(), POLLIN, 0};
        const int ready = poll(&p, 1, static_cast<int>(left.count()));
        if (ready < 0) {
            if (errno == EINTR)
                continue;
            throw DeviceError(DeviceKind::display, d.name, "poll failed: " + errno_text(errno));
        }
        if (ready > 0 && drmHandleEvent(d.fd.get(), &context) != 0)
            throw DeviceError(DeviceKind::display, d.name,
                              "reading the flip event failed: " + errno_text(errno));
    }
    const FlipEvent event = *d.completed;
    d.completed.reset();
    d.pending.reset();
    d.log.push_back(event);
    return event;
}

void DrmDisplay::restore() {
    Impl& d = *impl_;
    if (d.restored || !d.fd.valid())
        return;
    if (d.pending) {
        try {
            (void)wait_flip(std::chrono::milliseconds(500));
        } catch (const DeviceError&) {
            d.pending.reset(); // the kernel completes or drops it with the fd
        }
    }
    if (d.mode_set) {
        const drmModeCrtc* saved = d.saved_crtc.get();
        if (saved != nullptr && saved->mode_valid) {
            drmModeModeInfo saved_mode = saved->mode;
            drmModeSetCrtc(d.fd.get(), saved->crtc_id, saved->buffer_id, saved->x, saved->y,
                           &d.connector_id, 1, &saved_mode);
        } else {
            drmModeSetCrtc(d.fd.get(), d.crtc_id, 0, 0, 0, nullptr, 0, nullptr);
        }
        d.mode_set = false;
    }
    d.buffers.clear();
    d.mode_blob.reset();
    d.restored = true;
}

} // namespace fpp::drivers
