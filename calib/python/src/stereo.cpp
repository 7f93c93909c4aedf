// fpp.StereoCalibration: a camera-projector pair calibrated as a stereo pair
// (fpp/calib/stereo_calibration.hpp: ours, SLStudio's, SLMaster's files) and
// the stereo-vision reconstruction of a decode (fpp/calib/sv_reconstruct.hpp).
#include "arrays.hpp"
#include "bindings.hpp"
#include "decode.hpp"

#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/error.hpp"

#include <pybind11/stl/filesystem.h>

#include <limits>
#include <memory>
#include <mutex>

namespace fpp::python {

namespace {

using calib::StereoCalibration;

struct Stereo {
    StereoCalibration calibration;
    std::filesystem::path path;
    std::mutex mutex; // guards the reconstructor's cache
    std::shared_ptr<const calib::SvReconstructor> reconstructor;
    int reconstructor_threads = -1;
};

std::string size_text(Size s) {
    return std::to_string(s.width) + "x" + std::to_string(s.height);
}

py::array matrix(const LensModel& lens) {
    py::array_t<double> k({3, 3});
    double* p = k.mutable_data();
    const double values[9] = {lens.fu, lens.skew, lens.cu, 0, lens.fv, lens.cv, 0, 0, 1};
    std::copy(values, values + 9, p);
    return k;
}

py::array distortion(const LensModel& lens) {
    py::array_t<double> d(5);
    double* p = d.mutable_data();
    const double values[5] = {lens.k1, lens.k2, lens.p1, lens.p2, lens.k3}; // OpenCV's order
    std::copy(values, values + 5, p);
    return d;
}

// The size a file did not record, taken from the decode; one it did must agree.
void settle(Size& size, Size decoded, const Stereo& s, const char* key, const char* what) {
    if (size.width <= 0 || size.height <= 0) {
        size = decoded;
    } else if (size != decoded) {
        throw InputError(s.path, key,
                         std::string("the calibration is for a ") + size_text(size) + " " + what +
                             ", the decode's is " + size_text(decoded));
    }
}

// A decode given as arrays (StereoCalibration.reconstruct(proj_x, proj_y=,
// mask=)): proj_x and proj_y copied as float32, NaN where `mask` is False.
DecodeResult decode_of_arrays(py::handle proj_x, py::handle proj_y, py::handle mask) {
    DecodeResult r;
    r.proj_x = float_image(proj_x, "proj_x", 1);
    r.camera = r.proj_x.size();
    if (!proj_y.is_none())
        r.proj_y = float_image(proj_y, "proj_y", 1, r.camera);
    if (mask.is_none())
        return r;
    const std::string want =
        "mask: expected an (H, W) array of booleans (H, W = " + std::to_string(r.camera.height) +
        ", " + std::to_string(r.camera.width) + ")";
    py::array m = py::module_::import("numpy").attr("asarray")(mask);
    const char kind = m.dtype().kind();
    if (kind != 'b' && kind != 'u' && kind != 'i')
        throw py::type_error(want + ", got dtype " + py::str(m.dtype()).cast<std::string>());
    if (m.ndim() != 2 || m.shape(0) != r.camera.height || m.shape(1) != r.camera.width)
        throw py::type_error(want + ", got " + std::to_string(m.ndim()) + " dimensions of " +
                             py::str(m.attr("shape")).cast<std::string>());
    // Non-zero = valid, as booleans (contiguous; a view when it already is).
    const auto valid = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(
        m.attr("astype")("bool"));
    if (!valid)
        throw py::type_error(want);
    const bool* v = valid.data();
    float* x = r.proj_x.data();
    float* y = r.proj_y.empty() ? nullptr : r.proj_y.data();
    constexpr float nan = std::numeric_limits<float>::quiet_NaN();
    for (std::size_t i = 0, n = r.camera.area(); i < n; ++i) {
        if (!v[i]) {
            x[i] = nan;
            if (y)
                y[i] = nan;
        }
    }
    return r;
}

py::object reconstruct(Stereo& s, py::handle source, py::handle proj_y, py::handle mask,
                       py::handle projector, const std::string& axes_name, int threads) {
    // The decode: an fpp.DecodeResult (its arrays read in place) or arrays.
    std::shared_ptr<const DecodeResult> result;
    Size projector_size;
    if (py::isinstance<DecodeOutput>(source)) {
        if (!proj_y.is_none() || !mask.is_none() || !projector.is_none())
            throw py::type_error("StereoCalibration.reconstruct: a DecodeResult carries its own "
                                 "proj_y, mask and projector size; give proj_y=, mask= and "
                                 "projector= only with a proj_x array");
        const auto& decoded = source.cast<const DecodeOutput&>();
        result = decoded.result;
        projector_size = decoded.projector;
    } else {
        result = std::make_shared<const DecodeResult>(decode_of_arrays(source, proj_y, mask));
        if (!projector.is_none())
            projector_size = size_from(projector, "projector");
    }
    calib::ReconstructAxes axes;
    try {
        axes = calib::parse_axes(axes_name);
    } catch (const std::invalid_argument&) {
        throw InputError("StereoCalibration.reconstruct", "axes",
                         "must be 'auto', 'x' or 'xy', got '" + axes_name + "'");
    }
    if (threads < 0 || threads > 1024)
        throw InputError("StereoCalibration.reconstruct", "threads",
                         "must be in [0, 1024], got " + std::to_string(threads));
    PointCloud cloud;
    calib::SvStats stats;
    {
        py::gil_scoped_release release;
        std::shared_ptr<const calib::SvReconstructor> reconstructor;
        {
            const std::lock_guard lock(s.mutex);
            settle(s.calibration.camera_size, result->camera, s, "camera_size", "camera");
            if (projector_size.area() > 0)
                settle(s.calibration.projector_size, projector_size, s, "projector_size",
                       "projector");
            else if (s.calibration.projector_size.area() == 0)
                throw InputError(s.path, "projector_size",
                                 "the calibration does not record the projector's size: give "
                                 "projector=(width, height) with proj_x arrays");
            if (!s.reconstructor || s.reconstructor_threads != threads) {
                calib::SvOptions options;
                options.threads = threads;
                s.reconstructor =
                    std::make_shared<const calib::SvReconstructor>(s.calibration, options);
                s.reconstructor_threads = threads;
            }
            reconstructor = s.reconstructor;
        }
        stats = reconstructor->reconstruct(*result, axes, cloud);
    }
    py::object cloud_type = py::module_::import("fpp.cloud").attr("Cloud");
    py::object made = cloud_type(py::arg("xyz") = take_array(std::move(cloud.xyz)),
                                 py::arg("quality") = take_array(std::move(cloud.quality)),
                                 py::arg("intensity") = take_array(std::move(cloud.intensity)));
    py::dict figures;
    figures["axes"] = calib::to_string(stats.axes);
    figures["decoded"] = stats.decoded;
    figures["points"] = stats.points;
    figures["not_converged"] = stats.not_converged;
    figures["outside_projector"] = stats.outside_projector;
    figures["rejected"] = stats.rejected;
    figures["rms_ray_gap_mm"] = stats.rms_ray_gap_mm;
    figures["max_ray_gap_mm"] = stats.max_ray_gap_mm;
    made.attr("stats") = figures;
    return made;
}

} // namespace

void bind_stereo(py::module_& m) {
    py::class_<Stereo, std::shared_ptr<Stereo>>(
        m, "StereoCalibration",
        "A camera-projector pair calibrated as a stereo pair (projector as an inverse\n"
        "camera). Camera frame = world frame, mm; the projector frame is reached by\n"
        "X_p = R X_c + T. Lenses: pinhole with skew, Brown-Conrady distortion (OpenCV's\n"
        "formula), pixel centres on integers. Load with StereoCalibration.load(path).")
        .def_static(
            "load",
            [](const std::filesystem::path& path, const std::string& format) {
                calib::CalibrationFormat f;
                try {
                    f = calib::parse_calibration_format(format);
                } catch (const std::invalid_argument&) {
                    throw InputError("StereoCalibration.load", "format",
                                     "must be 'auto', 'fpp', 'slstudio' or 'slmaster', got '" +
                                         format + "'");
                }
                auto s = std::make_shared<Stereo>();
                s->path = path;
                py::gil_scoped_release release;
                s->calibration = calib::load_calibration(path, f);
                return s;
            },
            py::arg("path"), py::arg("format") = "auto",
            "Loads a calibration file: fpp's own (fpp-stereo/1), SLStudio's calibration.xml\n"
            "or SLMaster's caliInfo.yml, found by content with format='auto' or named\n"
            "('fpp', 'slstudio', 'slmaster').\n\n"
            "Raises fpp.InputError naming the file and the missing or malformed key (a\n"
            "camera-camera file: what it is and what it allows).")
        .def("reconstruct", &reconstruct, py::arg("result"), py::arg("proj_y") = py::none(),
             py::kw_only(), py::arg("mask") = py::none(), py::arg("projector") = py::none(),
             py::arg("axes") = "auto", py::arg("threads") = 0,
             "Stereo-vision reconstruction of a decode: per camera pixel, the point whose\n"
             "projection gives the decoded projector coordinate(s) (the paper's SV model,\n"
             "both lenses' distortion compensated).\n\n"
             "result: an fpp.DecodeResult of this camera (sizes the file did not record are\n"
             "  taken from it; ones it did must agree: fpp.InputError otherwise), or a\n"
             "  proj_x array: (H, W) projector x per camera pixel (any real dtype, copied as\n"
             "  float32; NaN = not decoded), with optionally\n"
             "proj_y: the same for the projector row (H, W), and\n"
             "mask: (H, W) booleans (or integers, non-zero = valid): False drops the pixel\n"
             "  (as a DecodeResult's mask), and\n"
             "projector: (width, height), needed when the file does not record it.\n"
             "  The same arrays give the same cloud, bit for bit, as their DecodeResult.\n"
             "  Wrong dtypes or shapes: TypeError naming the argument.\n"
             "axes: 'x' (projector column), 'xy' (column and row: the midpoint of the rays'\n"
             "  common perpendicular), 'auto' (xy when both are decoded).\n"
             "threads: worker threads, 0 = all cores.\n\n"
             "Returns an fpp.Cloud: xyz (H, W, 3) float32, camera frame, mm, NaN where no\n"
             "point; quality = modulation, intensity = mean (camera DN); .stats holds the\n"
             "counts (points, not_converged, outside_projector, rejected, ray gaps in mm).\n"
             "The GIL is released while it runs.")
        .def(
            "save",
            [](const Stereo& s, const std::filesystem::path& path) {
                py::gil_scoped_release release;
                calib::save_calibration(path, s.calibration);
            },
            py::arg("path"),
            "Writes the calibration in fpp's format (fpp-stereo/1), atomically. Raises\n"
            "ValueError when it cannot be represented (sizes unknown: reconstruct once, or\n"
            "a file that records them).")
        .def_property_readonly(
            "path", [](const Stereo& s) { return s.path; }, "The file it was loaded from.")
        .def_property_readonly(
            "format", [](const Stereo& s) { return calib::to_string(s.calibration.format); },
            "The format it was read from ('fpp', 'slstudio', 'slmaster').")
        .def_property_readonly(
            "camera_size",
            [](const Stereo& s) -> py::object {
                if (s.calibration.camera_size.area() == 0)
                    return py::none();
                return size_tuple(s.calibration.camera_size);
            },
            "Camera image size (width, height), or None if the file records none.")
        .def_property_readonly(
            "projector_size",
            [](const Stereo& s) -> py::object {
                if (s.calibration.projector_size.area() == 0)
                    return py::none();
                return size_tuple(s.calibration.projector_size);
            },
            "Projector image size (width, height), or None if the file records none.")
        .def_property_readonly(
            "camera_matrix", [](const Stereo& s) { return matrix(s.calibration.camera); },
            "Camera K (3 x 3: fu, skew, cu / 0, fv, cv / 0, 0, 1), pixels.")
        .def_property_readonly(
            "camera_distortion", [](const Stereo& s) { return distortion(s.calibration.camera); },
            "Camera distortion (k1, k2, p1, p2, k3), OpenCV's order.")
        .def_property_readonly(
            "projector_matrix", [](const Stereo& s) { return matrix(s.calibration.projector); },
            "Projector K (3 x 3), projector pixels.")
        .def_property_readonly(
            "projector_distortion",
            [](const Stereo& s) { return distortion(s.calibration.projector); },
            "Projector distortion (k1, k2, p1, p2, k3).")
        .def_property_readonly(
            "R",
            [](const Stereo& s) {
                py::array_t<double> r({3, 3});
                std::copy(s.calibration.R.begin(), s.calibration.R.end(), r.mutable_data());
                return r;
            },
            "Rotation camera -> projector (3 x 3): X_p = R X_c + T.")
        .def_property_readonly(
            "T",
            [](const Stereo& s) {
                py::array_t<double> t(3);
                std::copy(s.calibration.T.begin(), s.calibration.T.end(), t.mutable_data());
                return t;
            },
            "Translation camera -> projector, mm.")
        .def_property_readonly(
            "projector_centre",
            [](const Stereo& s) {
                const Vec3 c = s.calibration.projector_centre();
                return py::make_tuple(c[0], c[1], c[2]);
            },
            "The projector's centre in the camera frame, mm (-R^T T).")
        .def_property_readonly(
            "camera_rms",
            [](const Stereo& s) -> py::object {
                return s.calibration.camera_rms < 0
                           ? py::object(py::none())
                           : py::object(py::float_(s.calibration.camera_rms));
            },
            "Camera reprojection RMS, px (None if unknown).")
        .def_property_readonly(
            "projector_rms",
            [](const Stereo& s) -> py::object {
                return s.calibration.projector_rms < 0
                           ? py::object(py::none())
                           : py::object(py::float_(s.calibration.projector_rms));
            },
            "Projector reprojection RMS, px (None if unknown).")
        .def("__repr__", [](const Stereo& s) {
            return "<fpp.StereoCalibration " + s.path.string() + " (" +
                   calib::to_string(s.calibration.format) + ")>";
        });
}

} // namespace fpp::python
