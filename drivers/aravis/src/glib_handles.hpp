#pragma once
// RAII owners for the GLib objects the Aravis driver holds: every GObject in a
// unique_ptr whose deleter drops our reference, every GError freed on scope
// exit. Private to the driver.
#include <glib-object.h>

#include <memory>
#include <string>

#include <fpp/drivers/device_error.hpp>

namespace fpp::drivers::glib {

struct ObjectUnref {
    void operator()(void* object) const noexcept {
        if (object != nullptr)
            g_object_unref(object);
    }
};

// Owns one reference of a GObject (transfer-full results of Aravis calls).
template <class T> using ObjectPtr = std::unique_ptr<T, ObjectUnref>;

// An out-parameter for GError: pass `error.out()` to a GLib call, then test
// it. Frees the error it holds when reused or destroyed.
class Error {
public:
    Error() = default;
    Error(const Error&) = delete;
    Error& operator=(const Error&) = delete;
    ~Error() { g_clear_error(&error_); }

    GError** out() {
        g_clear_error(&error_);
        return &error_;
    }
    explicit operator bool() const { return error_ != nullptr; }
    std::string message() const {
        return error_ != nullptr ? std::string(error_->message) : std::string("unknown error");
    }
    // Throws DeviceError(camera, device, what + ": " + message) if the call failed.
    void throw_if_set(const std::string& device, const std::string& what) const {
        if (error_ != nullptr)
            throw DeviceError(DeviceKind::camera, device, what + ": " + message());
    }

private:
    GError* error_ = nullptr;
};

} // namespace fpp::drivers::glib
