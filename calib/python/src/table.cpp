// fpp.Table: the hybrid model's coefficient table (fpp/coefficient_table.hpp)
// and its kernel (fpp/table_kernel.hpp).
#include "arrays.hpp"
#include "bindings.hpp"

#include "fpp/coefficient_table.hpp"
#include "fpp/parallel.hpp"
#include "fpp/table_kernel.hpp"

#include <pybind11/stl/filesystem.h>

#include <memory>
#include <optional>

namespace fpp::python {

namespace {

struct Table {
    CoefficientTable table;
    std::filesystem::path path;
};

// apply(): the table's kernel over the pool (threads 0: the process-wide
// pool); the cloud's xyz moved into the array returned (no copy).
py::object apply(const Table& t, py::handle proj_x, py::handle coordinate_sigma, int threads) {
    if (threads < 0 || threads > 1024)
        throw py::value_error("threads: must be in [0, 1024], got " + std::to_string(threads));
    const Size camera = t.table.info().camera;
    const Image<float> phase = float_image(proj_x, "proj_x", 1, camera);
    std::optional<Image<float>> sigma;
    if (!coordinate_sigma.is_none())
        sigma = float_image(coordinate_sigma, "coordinate_sigma", 1, camera);
    PointCloud cloud;
    {
        py::gil_scoped_release release;
        std::optional<ThreadPool> pool;
        if (threads > 0)
            pool.emplace(threads);
        apply_table(t.table, phase, cloud, pool ? &*pool : nullptr, sigma ? &*sigma : nullptr);
    }
    py::object xyz = take_array(std::move(cloud.xyz));
    if (!sigma)
        return xyz;
    return py::make_tuple(xyz, take_array(std::move(cloud.sigma_z)));
}

} // namespace

void bind_table(py::module_& m) {
    py::class_<Table, std::shared_ptr<Table>>(
        m, "Table",
        "A per-pixel coefficient table (.fpt, firmware/core/formats/coefficient-table.md):\n"
        "the hybrid model that turns a camera pixel's decoded projector column into X, Y, Z\n"
        "(camera frame, mm). Load with fpp.Table.load(path); apply with table.apply(proj_x).")
        .def_static(
            "load",
            [](const std::filesystem::path& path, py::handle camera, bool map) {
                std::optional<Size> expected;
                if (!camera.is_none())
                    expected = size_from(camera, "camera");
                auto t = std::make_shared<Table>();
                t->path = path;
                py::gil_scoped_release release;
                t->table = load_table(path, expected ? &*expected : nullptr, map);
                return t;
            },
            py::arg("path"), py::arg("camera") = py::none(), py::arg("map") = true,
            "Loads a table file, memory-mapped read-only (map=False reads it into memory),\n"
            "checking its header, size and every tile's CRC-32.\n\n"
            "camera: optional (width, height) the table must be for.\n"
            "Raises fpp.InputError naming the file and the field (e.g. 'tile 17 crc',\n"
            "'camera_size'), OSError when it cannot be read.")
        .def("apply", &apply, py::arg("proj_x"), py::kw_only(),
             py::arg("coordinate_sigma") = py::none(), py::arg("threads") = 0,
             "The table applied to a decoded projector column: X, Y, Z per camera pixel.\n\n"
             "proj_x: (H, W) array of the table's camera size, projector x in projector\n"
             "  pixels (pixel centres on integers), NaN where not decoded (a DecodeResult's\n"
             "  proj_x); other real dtypes are converted, other shapes a TypeError.\n"
             "coordinate_sigma: optional (H, W) predicted standard deviation of proj_x,\n"
             "  projector px; then sigma_z (mm) is returned too.\n"
             "threads: worker threads, 0 = all cores (the process-wide pool).\n\n"
             "Returns an (H, W, 3) float32 array of X, Y, Z: camera frame, mm, NaN where\n"
             "there is no point (not decoded, no model, or outside the calibrated phase\n"
             "range); with coordinate_sigma, the tuple (xyz, sigma_z). The array is the\n"
             "kernel's own output (no copy). The GIL is released while it runs.")
        .def_property_readonly(
            "path", [](const Table& t) { return t.path; }, "The file it was loaded from.")
        .def_property_readonly(
            "camera", [](const Table& t) { return size_tuple(t.table.info().camera); },
            "Camera image size (width, height) the table is for.")
        .def_property_readonly(
            "projector", [](const Table& t) { return size_tuple(t.table.info().projector); },
            "Projector image size (width, height) the phase refers to.")
        .def_property_readonly(
            "model", [](const Table& t) { return std::string(to_string(t.table.info().model)); },
            "'polynomial', 'ray' or 'rational' (fpp/coefficient_table.hpp).")
        .def_property_readonly(
            "phase_axis",
            [](const Table& t) { return t.table.info().phase_axis == Axis::x ? "x" : "y"; },
            "The projector axis the phase is along ('x').")
        .def_property_readonly(
            "mapped", [](const Table& t) { return t.table.mapped(); },
            "Whether the coefficients are a read-only mapping of the file.")
        .def_property_readonly(
            "calibration_hash", [](const Table& t) { return t.table.info().calibration_hash; },
            "FNV-1a 64 of the source calibration file's bytes.")
        .def_property_readonly(
            "trueness",
            [](const Table& t) -> py::object {
                const TableTrueness& tr = t.table.info().trueness;
                if (!tr.known())
                    return py::none();
                py::dict d;
                d["length_mm"] = tr.length_mm;
                d["depth_mm"] = tr.depth_mm;
                d["along_depth_mm"] = tr.along_depth_mm;
                d["across_mm"] = tr.across_mm;
                return d;
            },
            "The calibration's predicted one-sigma length error (mm) along depth and across\n"
            "for a length_mm length at depth_mm, or None when unknown.")
        .def("__repr__", [](const Table& t) {
            const TableInfo& i = t.table.info();
            return "<fpp.Table " + t.path.string() + ": " + to_string(i.model) + ", camera " +
                   std::to_string(i.camera.width) + "x" + std::to_string(i.camera.height) + ">";
        });
}

} // namespace fpp::python
