// Aravis's in-process GigE Vision fake camera with a caller-supplied image.
#include <fpp/drivers/aravis_fake_camera.hpp>

#include <fpp/drivers/device_error.hpp>
#include <fpp/unique_fd.hpp>

#include "glib_handles.hpp"

#include <arv.h>

#include <net/if.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <bit>
#include <cstring>
#include <mutex>
#include <stdexcept>

namespace fpp::drivers {

struct AravisFakeCamera::Impl {
    std::string address;
    Size size;
    glib::ObjectPtr<ArvGvFakeCamera> camera;
    mutable std::mutex mutex; // guards `image`
    Frame image;
    std::atomic<std::uint64_t> frames_sent{0};

    // Runs on the fake camera's thread for every frame it sends.
    static void fill(ArvBuffer* buffer, void* user_data, guint32 /*exposure_us*/, guint32 /*gain*/,
                     ArvPixelFormat format) {
        auto* self = static_cast<Impl*>(user_data);
        const int width = arv_buffer_get_image_width(buffer);
        const int height = arv_buffer_get_image_height(buffer);
        const int bytes_per_pixel = int(ARV_PIXEL_FORMAT_BIT_PER_PIXEL(format)) / 8;
        // The fake camera sizes its buffer from the region and format at
        // stream start; the size Aravis reports here does not include it.
        auto* out =
            static_cast<std::uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, nullptr)));
        if (out == nullptr || width <= 0 || height <= 0)
            return;
        const std::size_t n = std::size_t(width) * std::size_t(height);

        const std::lock_guard lock(self->mutex);
        const Frame& image = self->image;
        const bool fits = image.size() == Size{width, height};
        if (bytes_per_pixel == 1) {
            if (!fits) {
                std::memset(out, 0, n);
            } else if (image.bit_depth == 8) {
                std::memcpy(out, image.u8.data(), n);
            } else {
                const std::uint16_t* in = image.u16.data();
                for (std::size_t i = 0; i < n; ++i)
                    out[i] = static_cast<std::uint8_t>(in[i] >> 8);
            }
        } else if (bytes_per_pixel == 2) {
            // Mono16 on the wire: little-endian samples.
            for (std::size_t i = 0; i < n; ++i) {
                std::uint16_t v = 0;
                if (fits)
                    v = image.bit_depth == 8 ? static_cast<std::uint16_t>(image.u8.data()[i] << 8)
                                             : image.u16.data()[i];
                out[2 * i] = static_cast<std::uint8_t>(v & 0xFF);
                out[2 * i + 1] = static_cast<std::uint8_t>(v >> 8);
            }
        } else {
            return; // colour formats: leave the buffer as it is
        }
        ++self->frames_sent;
    }
};

AravisFakeCamera::AravisFakeCamera(Size size, const std::string& address, const std::string& serial)
    : impl_(std::make_unique<Impl>()) {
    Impl& d = *impl_;
    d.address = address;
    d.size = size;
    if (size.width <= 0 || size.height <= 0 || size.width > 2048 || size.height > 2048)
        throw std::invalid_argument("fake camera size must lie in [1, 2048] x [1, 2048]");
    d.image.bit_depth = 8;
    d.image.u8 = Image<std::uint8_t>(size);

    d.camera.reset(arv_gv_fake_camera_new(address.c_str(), serial.c_str()));
    if (!d.camera || !arv_gv_fake_camera_is_running(d.camera.get()))
        throw DeviceError(DeviceKind::camera, "fake camera " + address,
                          "cannot start (address not local, or port 3956 taken by another "
                          "fake camera in this network namespace)");
    ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(d.camera.get());
    // Region registers of the fake camera (arvfakecamera.h): the image size.
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH, guint32(size.width));
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT, guint32(size.height));
    arv_fake_camera_set_fill_pattern(fake, &Impl::fill, &d);
    arv_fake_camera_set_trigger_frequency(fake, 1000.0);
}

AravisFakeCamera::~AravisFakeCamera() {
    // Stops the camera's thread before `impl_` (its fill data) goes.
    impl_->camera.reset();
}

void AravisFakeCamera::set_image(const Frame& frame) {
    if (frame.size() != impl_->size)
        throw std::invalid_argument("fake camera image must be " +
                                    std::to_string(impl_->size.width) + "x" +
                                    std::to_string(impl_->size.height));
    const std::lock_guard lock(impl_->mutex);
    impl_->image = frame;
}

void AravisFakeCamera::set_trigger_poll_rate(double hz) {
    if (!(hz > 0.0))
        throw std::invalid_argument("trigger poll rate must be positive");
    arv_fake_camera_set_trigger_frequency(arv_gv_fake_camera_get_fake_camera(impl_->camera.get()),
                                          hz);
}

std::uint64_t AravisFakeCamera::frames_sent() const {
    return impl_->frames_sent.load();
}
const std::string& AravisFakeCamera::address() const {
    return impl_->address;
}

bool enter_private_network_namespace() {
    if (unshare(CLONE_NEWNET) != 0)
        return false;
    // A new namespace has only a loopback interface, and it is down.
    const UniqueFd fd(socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
    if (!fd.valid())
        return false;
    ifreq request{};
    std::strncpy(request.ifr_name, "lo", IFNAMSIZ - 1);
    bool up = ioctl(fd.get(), SIOCGIFFLAGS, &request) == 0;
    if (up) {
        request.ifr_flags = static_cast<short>(request.ifr_flags | IFF_UP | IFF_RUNNING);
        up = ioctl(fd.get(), SIOCSIFFLAGS, &request) == 0;
    }
    return up;
}

} // namespace fpp::drivers
