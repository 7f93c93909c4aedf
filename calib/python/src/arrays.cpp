#include "arrays.hpp"

#include <cstring>

namespace fpp::python {

namespace {

py::array as_array(py::handle value) {
    if (py::isinstance<py::array>(value))
        return py::reinterpret_borrow<py::array>(value);
    return py::module_::import("numpy").attr("asarray")(value);
}

std::string shape_text(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i)
        s += (i ? ", " : "") + std::to_string(a.shape(i));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string dtype_text(const py::array& a) {
    return py::str(a.dtype()).cast<std::string>();
}

template <class T> void copy_into(const py::array& a, T* out) {
    const auto c = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(a);
    if (!c)
        throw py::error_already_set();
    std::memcpy(out, c.data(), std::size_t(c.size()) * sizeof(T));
}

} // namespace

Image<float> float_image(py::handle value, const std::string& name, int channels, Size expected) {
    const py::array a = as_array(value);
    const std::string want =
        (channels == 1 ? std::string("an (H, W)") : "an (H, W, " + std::to_string(channels) + ")") +
        " array of reals (float32" +
        (expected.area()
             ? ", H, W = " + std::to_string(expected.height) + ", " + std::to_string(expected.width)
             : std::string()) +
        ")";
    const char kind = a.dtype().kind();
    if (kind != 'f' && kind != 'i' && kind != 'u')
        throw py::type_error(name + ": expected " + want + ", got dtype " + dtype_text(a));
    const bool shape_ok = channels == 1 ? a.ndim() == 2 || (a.ndim() == 3 && a.shape(2) == 1)
                                        : a.ndim() == 3 && a.shape(2) == channels;
    if (!shape_ok || a.shape(0) < 1 || a.shape(1) < 1 ||
        (expected.area() && (a.shape(0) != expected.height || a.shape(1) != expected.width)))
        throw py::type_error(name + ": expected " + want + ", got shape " + shape_text(a));
    Image<float> image(int(a.shape(1)), int(a.shape(0)), channels);
    copy_into(a, image.data());
    return image;
}

namespace {

// `value` as a frame's array: uint8 or uint16, (H, W) or (H, W, 1), rows
// contiguous (a view of it, or a contiguous copy when its layout is not).
py::array frame_array(py::handle value, const std::string& name) {
    const py::array a = as_array(value);
    const std::string want = "an (H, W) uint8 or uint16 array (a grey camera frame)";
    const bool u8 = a.dtype().is(py::dtype::of<std::uint8_t>());
    const bool u16 = a.dtype().is(py::dtype::of<std::uint16_t>());
    if (!u8 && !u16)
        throw py::type_error(name + ": expected " + want + ", got dtype " + dtype_text(a) +
                             " (convert with .astype(numpy.uint8) or .astype(numpy.uint16))");
    if (!(a.ndim() == 2 || (a.ndim() == 3 && a.shape(2) == 1)) || a.shape(0) < 1 || a.shape(1) < 1)
        throw py::type_error(name + ": expected " + want + ", got shape " + shape_text(a));
    py::array c = u8 ? py::array(py::array_t<std::uint8_t, py::array::c_style>::ensure(a))
                     : py::array(py::array_t<std::uint16_t, py::array::c_style>::ensure(a));
    if (!c)
        throw py::type_error(name + ": expected " + want + " (no contiguous copy could be made)");
    return c;
}

FrameView view_of_array(const py::array& c) {
    FrameView view;
    view.bit_depth = c.itemsize() == 1 ? 8 : 16;
    view.size = {int(c.shape(1)), int(c.shape(0))};
    view.data = c.data();
    return view;
}

} // namespace

Frame frame_from_array(py::handle value, const std::string& name) {
    const FrameView view = view_of_array(frame_array(value, name));
    Frame frame;
    frame.bit_depth = view.bit_depth;
    if (view.bit_depth == 8) {
        frame.u8 = Image<std::uint8_t>(view.size);
        std::memcpy(frame.u8.data(), view.data, view.sample_count());
    } else {
        frame.u16 = Image<std::uint16_t>(view.size);
        std::memcpy(frame.u16.data(), view.data, view.sample_count() * 2);
    }
    return frame;
}

FrameView frame_view_from_array(py::handle value, const std::string& name, py::list& keep) {
    py::array c = frame_array(value, name);
    const FrameView view = view_of_array(c);
    keep.append(std::move(c));
    return view;
}

Size size_from(py::handle value, const std::string& name) {
    const std::string want = name + ": expected (width, height), two positive integers";
    if (!py::isinstance<py::sequence>(value) || py::isinstance<py::str>(value))
        throw py::type_error(want + ", got " + py::str(py::type::of(value)).cast<std::string>());
    const auto seq = py::reinterpret_borrow<py::sequence>(value);
    if (seq.size() != 2)
        throw py::type_error(want + ", got " + std::to_string(seq.size()) + " values");
    Size size;
    for (int i = 0; i < 2; ++i) {
        const py::handle v = seq[std::size_t(i)];
        if (!py::isinstance<py::int_>(v) || py::isinstance<py::bool_>(v))
            throw py::type_error(want + ", got " + py::repr(v).cast<std::string>());
        const long n = v.cast<long>();
        if (n < 1 || n > 65535)
            throw py::value_error(want + " up to 65535, got " + std::to_string(n));
        (i == 0 ? size.width : size.height) = int(n);
    }
    return size;
}

py::tuple size_tuple(Size size) {
    return py::make_tuple(size.width, size.height);
}

} // namespace fpp::python
