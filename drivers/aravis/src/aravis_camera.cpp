// Aravis 0.8 camera driver. Every Aravis object is owned by a glib::ObjectPtr;
// a popped buffer is owned by a BufferLease that pushes it back to the stream
// on every path out of next_frame().
#include <fpp/drivers/aravis_camera.hpp>

#include <fpp/drivers/device_error.hpp>
#include <fpp/drivers/gige_frame_ids.hpp>
#include <fpp/enum_names.hpp>
#include <fpp/error.hpp>

#include "glib_handles.hpp"

#include <arv.h>

#include <netinet/in.h>
#include <sys/socket.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <optional>
#include <string>

namespace fpp::drivers {
namespace {

// Sets SO_RCVBUF on this process's IPv4 UDP socket bound to `port` (Aravis
// does not hand out its stream socket). Best effort: the buffer only guards
// against packet loss, so a socket not found is left as it is.
void size_receive_buffer(unsigned port, int bytes) {
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd", ec)) {
        int fd = -1;
        const std::string name = entry.path().filename().string();
        const auto [end, parse_error] = std::from_chars(name.data(), name.data() + name.size(), fd);
        if (parse_error != std::errc{} || end != name.data() + name.size())
            continue;
        sockaddr_in address{};
        socklen_t length = sizeof address;
        int type = 0;
        socklen_t type_length = sizeof type;
        // reinterpret_cast: the sockets API takes the generic address type.
        if (getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0 ||
            address.sin_family != AF_INET || ntohs(address.sin_port) != port ||
            getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &type_length) != 0 || type != SOCK_DGRAM)
            continue;
        setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
    }
}

constexpr const char* kSettings = "camera settings";

struct PixelLayout {
    int container_bits; // 8 or 16
    int significant_bits;
};

std::optional<PixelLayout> layout_of(const std::string& pixel_format) {
    if (pixel_format == "Mono8")
        return PixelLayout{8, 8};
    if (pixel_format == "Mono10")
        return PixelLayout{16, 10};
    if (pixel_format == "Mono12")
        return PixelLayout{16, 12};
    if (pixel_format == "Mono14")
        return PixelLayout{16, 14};
    if (pixel_format == "Mono16")
        return PixelLayout{16, 16};
    return std::nullopt;
}

std::int64_t clock_ns(clockid_t clock) {
    timespec ts{};
    clock_gettime(clock, &ts);
    return std::int64_t(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// Aravis stamps buffers on arrival with the real-time clock; the interface
// speaks CLOCK_MONOTONIC, which steps with neither NTP nor the user.
std::int64_t realtime_to_monotonic_ns(std::uint64_t realtime_ns) {
    const std::int64_t offset = clock_ns(CLOCK_REALTIME) - clock_ns(CLOCK_MONOTONIC);
    return static_cast<std::int64_t>(realtime_ns) - offset;
}

constexpr EnumName<ArvBufferStatus> kBufferStatusTexts[] = {
    {ARV_BUFFER_STATUS_SUCCESS, "complete"},
    {ARV_BUFFER_STATUS_CLEARED, "cleared"},
    {ARV_BUFFER_STATUS_TIMEOUT, "timed out while being received"},
    {ARV_BUFFER_STATUS_MISSING_PACKETS, "missing packets"},
    {ARV_BUFFER_STATUS_WRONG_PACKET_ID, "wrong packet id"},
    {ARV_BUFFER_STATUS_SIZE_MISMATCH, "larger than the buffer"},
    {ARV_BUFFER_STATUS_FILLING, "still filling"},
    {ARV_BUFFER_STATUS_ABORTED, "aborted"},
};

const char* buffer_status_text(ArvBufferStatus status) {
    return name_of(kBufferStatusTexts, status, "failed");
}

// The buffer taken from the stream; goes back to it when the lease ends.
class BufferLease {
public:
    BufferLease(ArvStream* stream, ArvBuffer* buffer, std::atomic<int>& outstanding)
        : stream_(stream), buffer_(buffer), outstanding_(outstanding) {
        ++outstanding_;
    }
    ~BufferLease() {
        arv_stream_push_buffer(stream_, buffer_);
        --outstanding_;
    }
    BufferLease(const BufferLease&) = delete;
    BufferLease& operator=(const BufferLease&) = delete;
    ArvBuffer* get() const { return buffer_; }

private:
    ArvStream* stream_;
    ArvBuffer* buffer_;
    std::atomic<int>& outstanding_;
};

void validate(const CameraSettings& settings) {
    if (!layout_of(settings.pixel_format))
        throw InputError(kSettings, "pixel_format",
                         "'" + settings.pixel_format +
                             "' is not supported (Mono8, Mono10, Mono12, Mono14, Mono16)");
    // The camera's own bounds are checked once it is reached (configure()).
    if (!(settings.exposure_us > 0.0) || !std::isfinite(settings.exposure_us))
        throw InputError(kSettings, "exposure_us", "must be a positive number of microseconds");
    if (settings.trigger == TriggerMode::line && settings.trigger_source.empty())
        throw InputError(kSettings, "trigger_source", "a line trigger needs a source line");
    if (settings.packet_size < 0 || settings.packet_size > 16384)
        throw InputError(kSettings, "packet_size", "must lie in [0, 16384] bytes (0 = default)");
    if (settings.buffer_count < 2 || settings.buffer_count > 64)
        throw InputError(kSettings, "buffer_count", "must lie in [2, 64]");
    if (settings.frame_timeout.count() <= 0)
        throw InputError(kSettings, "frame_timeout", "must be positive");
}

// Microseconds as people write them: "10", "10000000", "2.5".
std::string format_us(double us) {
    char text[32];
    std::snprintf(text, sizeof text, "%.10g", us);
    return text;
}

// InputError naming the camera's range when `exposure_us` lies outside it.
void check_exposure(double exposure_us, const ExposureRange& range) {
    if (!(exposure_us > 0.0) || !range.contains(exposure_us))
        throw InputError(kSettings, "exposure_us",
                         format_us(exposure_us) + " us is outside the camera's exposure range " +
                             format_us(range.min_us) + ".." + format_us(range.max_us) + " us");
}

} // namespace

struct AravisCamera::Impl {
    std::string name;
    CameraSettings settings;
    PixelLayout layout{8, 8};
    Size size;
    ExposureRange exposure_range; // the camera's ExposureTime bounds, read at opening
    glib::ObjectPtr<ArvCamera> camera;
    glib::ObjectPtr<ArvStream> stream;
    gulong control_lost_handler = 0;
    std::atomic<bool> control_lost{false};
    std::atomic<int> outstanding{0};
    std::size_t payload = 0;
    bool streaming = false;
    // Set when a control command failed (GVCP retries exhausted): stop() then
    // does not wait on a camera that is gone.
    bool unreachable = false;
    std::optional<std::uint64_t> last_frame_id;
    std::uint64_t last_camera_timestamp = 0;

    void set_string(const char* feature, const std::string& value) {
        glib::Error error;
        arv_camera_set_string(camera.get(), feature, value.c_str(), error.out());
        error.throw_if_set(name, std::string("cannot set ") + feature + " = " + value);
    }

    void configure() {
        ArvCamera* cam = camera.get();
        glib::Error error;

        arv_camera_set_pixel_format_from_string(cam, settings.pixel_format.c_str(), error.out());
        error.throw_if_set(name, "cannot set PixelFormat = " + settings.pixel_format);

        // Cameras of SFNC 2 have ExposureTime, older ones ExposureTimeAbs; Aravis
        // picks the one present.
        arv_camera_get_exposure_time_bounds(cam, &exposure_range.min_us, &exposure_range.max_us,
                                            error.out());
        error.throw_if_set(name, "cannot read the ExposureTime bounds");
        if (!(exposure_range.min_us <= exposure_range.max_us) ||
            !std::isfinite(exposure_range.min_us) || !std::isfinite(exposure_range.max_us))
            throw DeviceError(DeviceKind::camera, name,
                              "reports an empty ExposureTime range " +
                                  format_us(exposure_range.min_us) + ".." +
                                  format_us(exposure_range.max_us) + " us");
        check_exposure(settings.exposure_us, exposure_range);
        arv_camera_set_exposure_time(cam, settings.exposure_us, error.out());
        error.throw_if_set(
            name, "cannot set ExposureTime = " + std::to_string(settings.exposure_us) + " us");

        arv_camera_set_acquisition_mode(cam, ARV_ACQUISITION_MODE_CONTINUOUS, error.out());
        error.throw_if_set(name, "cannot set AcquisitionMode = Continuous");

        set_string("TriggerSelector", "FrameStart");
        set_string("TriggerMode", "On");
        set_string("TriggerSource", settings.trigger == TriggerMode::software
                                        ? "Software"
                                        : settings.trigger_source);

        if (arv_camera_is_gv_device(cam) && settings.packet_size > 0) {
            arv_camera_gv_set_packet_size(cam, settings.packet_size, error.out());
            error.throw_if_set(name, "cannot set GevSCPSPacketSize = " +
                                         std::to_string(settings.packet_size));
        }

        gint x = 0, y = 0, width = 0, height = 0;
        arv_camera_get_region(cam, &x, &y, &width, &height, error.out());
        error.throw_if_set(name, "cannot read the image region");
        size = {width, height};

        const guint payload_bytes = arv_camera_get_payload(cam, error.out());
        error.throw_if_set(name, "cannot read the payload size");
        payload = payload_bytes;
        const std::size_t needed = size.area() * std::size_t(layout.container_bits / 8);
        if (payload < needed)
            throw DeviceError(DeviceKind::camera, name,
                              "payload of " + std::to_string(payload) +
                                  " bytes is smaller than a " + std::to_string(width) + "x" +
                                  std::to_string(height) + " " + settings.pixel_format + " image");
    }

    void create_stream() {
        glib::Error error;
        stream.reset(arv_camera_create_stream(camera.get(), nullptr, nullptr, error.out()));
        if (!stream)
            throw DeviceError(DeviceKind::camera, name,
                              "cannot open the stream: " + error.message());
        if (ARV_IS_GV_STREAM(stream.get())) {
            // Room in the UDP receive buffer for as many frames as the pool
            // holds (the kernel caps it at net.core.rmem_max), so that a
            // receiving thread that falls behind (a loaded board) loses no
            // packet. Aravis would size it to one frame, and only at the
            // first frame's leader: until then the kernel default
            // (net.core.rmem_default, 208 KiB) holds less than one frame, and
            // the first frame of every stream start could lose its tail.
            const auto bytes = static_cast<int>(
                std::min<std::size_t>(payload * std::size_t(settings.buffer_count), 1u << 30));
            g_object_set(stream.get(), "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED,
                         "socket-buffer-size", bytes, nullptr);
            size_receive_buffer(arv_gv_stream_get_port(ARV_GV_STREAM(stream.get())), bytes);
        }
        for (int i = 0; i < settings.buffer_count; ++i) {
            // The stream owns the buffers pushed to it and frees them with itself.
            arv_stream_push_buffer(stream.get(), arv_buffer_new_allocate(payload));
        }
    }

    // Returns buffers left in the output queue to the input queue.
    void recycle_queued_buffers() {
        while (ArvBuffer* buffer = arv_stream_try_pop_buffer(stream.get()))
            arv_stream_push_buffer(stream.get(), buffer);
    }

    Frame convert(ArvBuffer* buffer, std::uint64_t frame_id) const {
        const auto id = std::to_string(frame_id);
        if (arv_buffer_get_image_width(buffer) != size.width ||
            arv_buffer_get_image_height(buffer) != size.height)
            throw DeviceError(
                DeviceKind::camera, name,
                "frame " + id + " is " + std::to_string(arv_buffer_get_image_width(buffer)) + "x" +
                    std::to_string(arv_buffer_get_image_height(buffer)) + ", expected " +
                    std::to_string(size.width) + "x" + std::to_string(size.height));
        const ArvPixelFormat format = arv_buffer_get_image_pixel_format(buffer);
        const int bits = int(ARV_PIXEL_FORMAT_BIT_PER_PIXEL(format));
        if (bits != layout.container_bits)
            throw DeviceError(DeviceKind::camera, name,
                              "frame " + id + " has " + std::to_string(bits) +
                                  " bits per pixel, expected " + settings.pixel_format);
        std::size_t bytes = 0;
        const void* data = arv_buffer_get_image_data(buffer, &bytes);
        const std::size_t needed = size.area() * std::size_t(layout.container_bits / 8);
        if (data == nullptr || bytes < needed)
            throw DeviceError(DeviceKind::camera, name,
                              "frame " + id + " holds " + std::to_string(bytes) +
                                  " bytes, expected " + std::to_string(needed));

        Frame frame;
        frame.bit_depth = layout.container_bits;
        if (layout.container_bits == 8) {
            frame.u8 = Image<std::uint8_t>(size);
            std::memcpy(frame.u8.data(), data, needed);
            return frame;
        }
        // GenICam Mono10..16 are little-endian, LSB-aligned samples.
        frame.u16 = Image<std::uint16_t>(size);
        std::uint16_t* out = frame.u16.data();
        const auto* in = static_cast<const std::uint8_t*>(data);
        const int shift = 16 - layout.significant_bits;
        const std::size_t n = size.area();
        if constexpr (std::endian::native == std::endian::little) {
            std::memcpy(out, in, needed);
        } else {
            for (std::size_t i = 0; i < n; ++i)
                out[i] = static_cast<std::uint16_t>(in[2 * i] | (in[2 * i + 1] << 8));
        }
        if (shift > 0)
            for (std::size_t i = 0; i < n; ++i)
                out[i] = static_cast<std::uint16_t>(out[i] << shift);
        return frame;
    }

    // Records the frame as the latest, then throws if it did not follow its
    // predecessor (so that the frames after a gap are judged against it).
    void check_sequence(std::uint64_t frame_id, std::uint64_t camera_timestamp) {
        const std::optional<std::uint64_t> previous_id = last_frame_id;
        const std::uint64_t previous_timestamp = last_camera_timestamp;
        last_frame_id = frame_id;
        last_camera_timestamp = camera_timestamp;
        if (!previous_id)
            return;
        const std::uint64_t missed = gige_frames_missed(*previous_id, frame_id);
        if (missed == UINT64_MAX)
            throw DeviceError(DeviceKind::camera, name,
                              "frame " + std::to_string(frame_id) + " does not follow frame " +
                                  std::to_string(*previous_id));
        if (missed > 0)
            throw DeviceError(DeviceKind::camera, name,
                              std::to_string(missed) + " frame(s) missing: expected frame " +
                                  std::to_string(gige_next_frame_id(*previous_id)) +
                                  ", got frame " + std::to_string(frame_id));
        if (camera_timestamp != 0 && previous_timestamp != 0 &&
            camera_timestamp <= previous_timestamp)
            throw DeviceError(DeviceKind::camera, name,
                              "frame " + std::to_string(frame_id) +
                                  " is stamped no later than frame " +
                                  std::to_string(*previous_id));
    }
};

namespace {
void on_control_lost(ArvDevice*, gpointer user_data) {
    static_cast<std::atomic<bool>*>(user_data)->store(true);
}
} // namespace

AravisCamera::AravisCamera(const std::string& device, const CameraSettings& settings)
    : impl_(std::make_unique<Impl>()) {
    validate(settings);
    Impl& d = *impl_;
    d.name = "camera " + device;
    d.settings = settings;
    d.layout = *layout_of(settings.pixel_format);

    glib::Error error;
    d.camera.reset(arv_camera_new(device.c_str(), error.out()));
    if (!d.camera)
        throw DeviceError(DeviceKind::camera, d.name, "cannot open: " + error.message());

    ArvDevice* arv_device = arv_camera_get_device(d.camera.get());
    d.control_lost_handler = g_signal_connect_data(arv_device, "control-lost",
                                                   reinterpret_cast<GCallback>(on_control_lost),
                                                   &d.control_lost, nullptr, GConnectFlags(0));

    d.configure();
    d.create_stream();
}

AravisCamera::~AravisCamera() {
    if (!impl_)
        return;
    stop();
    Impl& d = *impl_;
    if (d.control_lost_handler != 0)
        g_signal_handler_disconnect(arv_camera_get_device(d.camera.get()), d.control_lost_handler);
    d.stream.reset(); // joins the receiving thread and frees the pool
    d.camera.reset();
}

Size AravisCamera::size() const {
    return impl_->size;
}
int AravisCamera::bit_depth() const {
    return impl_->layout.container_bits;
}
const std::string& AravisCamera::name() const {
    return impl_->name;
}
int AravisCamera::buffer_count() const {
    return impl_->settings.buffer_count;
}
int AravisCamera::buffers_outstanding() const {
    return impl_->outstanding.load();
}

void AravisCamera::start() {
    Impl& d = *impl_;
    if (d.streaming)
        return;
    d.recycle_queued_buffers();
    d.last_frame_id.reset();
    d.last_camera_timestamp = 0;
    glib::Error error;
    arv_camera_start_acquisition(d.camera.get(), error.out());
    d.unreachable = bool(error);
    error.throw_if_set(d.name, "cannot start acquisition");
    d.control_lost = false;
    d.streaming = true;
}

void AravisCamera::stop() {
    Impl& d = *impl_;
    if (!d.streaming)
        return;
    d.streaming = false;
    if (!d.unreachable && !d.control_lost) {
        glib::Error error;
        arv_camera_stop_acquisition(d.camera.get(), error.out());
        d.unreachable = bool(error);
    }
    d.recycle_queued_buffers();
}

ExposureRange AravisCamera::exposure_range_us() const {
    return impl_->exposure_range;
}

void AravisCamera::set_exposure_us(double exposure_us) {
    Impl& d = *impl_;
    check_exposure(exposure_us, d.exposure_range);
    if (d.streaming)
        throw DeviceError(DeviceKind::camera, d.name, "exposure changed while acquiring");
    glib::Error error;
    arv_camera_set_exposure_time(d.camera.get(), exposure_us, error.out());
    d.unreachable = bool(error);
    error.throw_if_set(d.name, "cannot set ExposureTime = " + std::to_string(exposure_us) + " us");
    d.settings.exposure_us = exposure_us;
}

void AravisCamera::software_trigger() {
    Impl& d = *impl_;
    if (d.settings.trigger != TriggerMode::software)
        throw DeviceError(DeviceKind::camera, d.name,
                          "software trigger requested but the camera is set to "
                          "trigger on " +
                              d.settings.trigger_source);
    if (!d.streaming)
        throw DeviceError(DeviceKind::camera, d.name, "software trigger while not started");
    glib::Error error;
    arv_camera_software_trigger(d.camera.get(), error.out());
    d.unreachable = bool(error);
    error.throw_if_set(d.name, "software trigger failed");
}

CapturedFrame AravisCamera::next_frame(std::chrono::milliseconds timeout) {
    Impl& d = *impl_;
    if (!d.streaming)
        throw DeviceError(DeviceKind::camera, d.name, "next_frame() while not started");
    const auto expected = d.last_frame_id
                              ? "frame " + std::to_string(gige_next_frame_id(*d.last_frame_id))
                              : std::string("first frame");
    const auto timeout_us = std::chrono::duration_cast<std::chrono::microseconds>(timeout);
    ArvBuffer* raw = arv_stream_timeout_pop_buffer(
        d.stream.get(), static_cast<guint64>(std::max<std::int64_t>(0, timeout_us.count())));
    if (raw == nullptr)
        throw DeviceError(DeviceKind::camera, d.name,
                          expected + " did not arrive within " + std::to_string(timeout.count()) +
                              " ms" + (d.control_lost ? " (control of the camera lost)" : ""));
    const BufferLease lease(d.stream.get(), raw, d.outstanding);

    CapturedFrame captured;
    captured.frame_id = arv_buffer_get_frame_id(raw);
    const ArvBufferStatus status = arv_buffer_get_status(raw);
    if (status != ARV_BUFFER_STATUS_SUCCESS) {
        // The frame is lost; what follows it is checked against it.
        d.last_frame_id = captured.frame_id;
        d.last_camera_timestamp = 0;
        throw DeviceError(DeviceKind::camera, d.name,
                          "frame " + std::to_string(captured.frame_id) +
                              " incomplete: " + buffer_status_text(status));
    }
    d.check_sequence(captured.frame_id, arv_buffer_get_timestamp(raw));
    captured.timestamp_ns = realtime_to_monotonic_ns(arv_buffer_get_system_timestamp(raw));
    captured.frame = d.convert(raw, captured.frame_id);
    return captured;
}

std::size_t AravisCamera::frames_waiting() const {
    gint n_input = 0;
    gint n_output = 0;
    arv_stream_get_n_buffers(impl_->stream.get(), &n_input, &n_output);
    return static_cast<std::size_t>(std::max(n_output, 0));
}

} // namespace fpp::drivers
