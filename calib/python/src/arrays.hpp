#pragma once
// NumPy arrays to and from fpp's images. Out: without a copy (the array owns
// the image, or views memory its owner keeps alive). In: copied into an
// fpp::Image (it owns its pixels), or for frames to decode borrowed
// (FrameView); another dtype converted where no value can change, else
// TypeError naming the argument and what was expected.

#include "fpp/image.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>
#include <utility>

namespace fpp::python {

namespace py = pybind11;

// A view of `image` as an (H, W) array, or (H, W, C) for C > 1 channels,
// kept alive by `owner` (the array's base); read-only unless `writeable`.
// None for an empty image.
template <class T>
py::object view_array(const Image<T>& image, py::handle owner, bool writeable = false) {
    if (image.empty())
        return py::none();
    const auto c = py::ssize_t(image.channels());
    const auto w = py::ssize_t(image.width());
    const auto h = py::ssize_t(image.height());
    const auto item = py::ssize_t(sizeof(T));
    std::vector<py::ssize_t> shape{h, w}, strides{w * c * item, c * item};
    if (c > 1) {
        shape.push_back(c);
        strides.push_back(item);
    }
    py::array array(py::dtype::of<T>(), std::move(shape), std::move(strides), image.data(), owner);
    if (!writeable) // numpy's flag itself (as arr.flags.writeable = False, without the lookups)
        py::detail::array_proxy(array.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    return array;
}

// `image` moved into an array that owns it (writeable). None when empty.
template <class T> py::object take_array(Image<T>&& image) {
    if (image.empty())
        return py::none();
    auto* owned = new Image<T>(std::move(image));
    py::capsule owner(owned, [](void* p) { delete static_cast<Image<T>*>(p); });
    return view_array(*owned, owner, true);
}

// `value` as a float32 image of `channels` channels: an (H, W) array for 1,
// (H, W, channels) otherwise; any real or integer dtype is converted, any
// layout copied. With `expected` (not 0 x 0), its height and width must be
// those. TypeError naming `name` otherwise.
Image<float> float_image(py::handle value, const std::string& name, int channels,
                         Size expected = {});

// A camera frame: an (H, W) (or (H, W, 1)) uint8 or uint16 array, any
// layout (copied). Other dtypes: TypeError naming `name` (a frame's depth is
// its container's, so no integer type is guessed into one).
Frame frame_from_array(py::handle value, const std::string& name);
// The same frame borrowed, not copied: a view of the array's samples when
// its rows are contiguous (else of a contiguous copy). The array viewed is
// appended to `keep`, which must outlive the view.
FrameView frame_view_from_array(py::handle value, const std::string& name, py::list& keep);

// (width, height) from a 2-sequence of positive integers; TypeError naming `name`.
Size size_from(py::handle value, const std::string& name);
py::tuple size_tuple(Size size);

} // namespace fpp::python
