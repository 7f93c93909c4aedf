// PLY files (fpp/point_cloud.hpp) for fpp.read_ply / fpp.write_ply
// (fpp/cloud.py builds the Cloud around these).
#include "arrays.hpp"
#include "bindings.hpp"

#include "fpp/error.hpp"
#include "fpp/point_cloud.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <limits>

namespace fpp::python {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The points of `ply` back in their camera pixels (`organised` x channels,
// NaN where no point), or None when the file has no such property.
py::object organise(const std::vector<float>* channel[], int channels, const PlyPoints& ply) {
    for (int c = 0; c < channels; ++c)
        if (channel[c]->empty())
            return py::none();
    Image<float> image(ply.organised, channels, kNaN);
    for (std::size_t i = 0; i < ply.size(); ++i)
        for (int c = 0; c < channels; ++c)
            image.data()[std::size_t(ply.pixel[i]) * std::size_t(channels) + std::size_t(c)] =
                (*channel[c])[i];
    return take_array(std::move(image));
}

// The same as a flat (N, channels) array (a cloud without pixel indices).
py::object flat(const std::vector<float>* channel[], int channels, std::size_t n) {
    for (int c = 0; c < channels; ++c)
        if (channel[c]->empty())
            return py::none();
    py::array_t<float> a(channels == 1 ? std::vector<py::ssize_t>{py::ssize_t(n)}
                                       : std::vector<py::ssize_t>{py::ssize_t(n), channels});
    float* out = a.mutable_data();
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < channels; ++c)
            out[i * std::size_t(channels) + std::size_t(c)] = (*channel[c])[i];
    return a;
}

py::dict read(const std::filesystem::path& path) {
    PlyPoints ply;
    {
        py::gil_scoped_release release;
        ply = read_ply(path);
    }
    const bool organised = ply.organised.area() > 0 && ply.pixel.size() == ply.size();
    if (organised)
        for (std::size_t i = 0; i < ply.size(); ++i)
            if (ply.pixel[i] >= ply.organised.area())
                throw InputError(path, "pixel",
                                 "vertex " + std::to_string(i) + " has pixel index " +
                                     std::to_string(ply.pixel[i]) + ", outside the organised " +
                                     std::to_string(ply.organised.width) + "x" +
                                     std::to_string(ply.organised.height) + " image");
    const std::vector<float>* xyz[] = {&ply.x, &ply.y, &ply.z};
    const std::vector<float>* quality[] = {&ply.quality};
    const std::vector<float>* intensity[] = {&ply.intensity};
    const std::vector<float>* sigma[] = {&ply.sigma_z};
    const auto take = [&](const std::vector<float>** c, int n) {
        return organised ? organise(c, n, ply) : flat(c, n, ply.size());
    };
    py::dict d;
    d["xyz"] = take(xyz, 3);
    d["quality"] = take(quality, 1);
    d["intensity"] = take(intensity, 1);
    d["sigma_z"] = take(sigma, 1);
    d["organised"] = organised;
    d["comments"] = ply.comments;
    if (!organised && !ply.pixel.empty()) {
        py::array_t<std::uint32_t> pixel(py::ssize_t(ply.pixel.size()));
        std::copy(ply.pixel.begin(), ply.pixel.end(), pixel.mutable_data());
        d["pixel"] = pixel;
    } else {
        d["pixel"] = py::none();
    }
    return d;
}

void write(const std::filesystem::path& path, py::handle xyz, py::handle quality,
           py::handle intensity, py::handle sigma_z, const std::vector<std::string>& comments) {
    PointCloud cloud;
    cloud.xyz = float_image(xyz, "xyz", 3);
    const Size size = cloud.xyz.size();
    if (!quality.is_none())
        cloud.quality = float_image(quality, "quality", 1, size);
    if (!intensity.is_none())
        cloud.intensity = float_image(intensity, "intensity", 1, size);
    if (!sigma_z.is_none())
        cloud.sigma_z = float_image(sigma_z, "sigma_z", 1, size);
    py::gil_scoped_release release;
    write_ply(path, cloud, comments);
}

} // namespace

void bind_ply(py::module_& m) {
    m.def("_read_ply", &read, py::arg("path"),
          "The arrays of a PLY file (fpp.read_ply builds the Cloud).");
    m.def("_write_ply", &write, py::arg("path"), py::arg("xyz"), py::arg("quality"),
          py::arg("intensity"), py::arg("sigma_z"), py::arg("comments"),
          "Writes the arrays of a Cloud as PLY (fpp.write_ply).");
}

} // namespace fpp::python
