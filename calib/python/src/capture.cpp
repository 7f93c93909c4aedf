#include "capture.hpp"

#include "arrays.hpp"
#include "bindings.hpp"

#include "fpp/error.hpp"
#include "fpp/image_io.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cstdio>
#include <regex>

namespace fpp::python {

namespace fs = std::filesystem;

// ---------------------------------------------------------------- Capture

Capture::Capture(fs::path folder)
    : folder_(std::move(folder)), manifest_(read_manifest(folder_ / "capture.yaml")) {}

Capture::Capture(CaptureSet set)
    : folder_(set.folder), manifest_(set.manifest),
      set_(std::make_shared<const CaptureSet>(std::move(set))) {}

bool Capture::loaded() const {
    const std::lock_guard lock(mutex_);
    return set_ != nullptr;
}

std::shared_ptr<const CaptureSet> Capture::set() {
    const std::lock_guard lock(mutex_);
    if (!set_)
        set_ = std::make_shared<const CaptureSet>(read_capture_set(folder_));
    return set_;
}

// ---------------------------------------------------------------- YAML <-> Python

namespace {

py::object scalar_to_py(const YAML::Node& node) {
    const std::string& s = node.Scalar();
    if (node.Tag() != "?") // quoted: text
        return py::str(s);
    if (s == "true")
        return py::bool_(true);
    if (s == "false")
        return py::bool_(false);
    if (s.empty() || s == "~" || s == "null")
        return py::none();
    long long i = 0;
    if (auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), i);
        ec == std::errc() && end == s.data() + s.size())
        return py::int_(i);
    double d = 0;
    if (auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), d);
        ec == std::errc() && end == s.data() + s.size())
        return py::float_(d);
    return py::str(s); // text, or a ratio such as 1920/58
}

py::object yaml_to_py(const YAML::Node& node) {
    if (node.IsMap()) {
        py::dict d;
        for (const auto& kv : node)
            d[py::str(kv.first.Scalar())] = yaml_to_py(kv.second);
        return d;
    }
    if (node.IsSequence()) {
        py::list l;
        for (const auto& item : node)
            l.append(yaml_to_py(item));
        return l;
    }
    if (node.IsScalar())
        return scalar_to_py(node);
    return py::none();
}

void py_to_yaml(YAML::Emitter& out, py::handle value) {
    static const std::regex ratio(R"([-+]?[0-9.eE+-]+/[0-9.eE+-]+)");
    if (py::isinstance<py::dict>(value)) {
        out << YAML::BeginMap;
        for (const auto& [k, v] : py::reinterpret_borrow<py::dict>(value)) {
            out << YAML::Key << py::str(k).cast<std::string>() << YAML::Value;
            py_to_yaml(out, v);
        }
        out << YAML::EndMap;
    } else if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
        out << YAML::BeginSeq;
        for (const auto& v : py::reinterpret_borrow<py::sequence>(value))
            py_to_yaml(out, v);
        out << YAML::EndSeq;
    } else if (py::isinstance<py::bool_>(value)) {
        out << (value.cast<bool>() ? "true" : "false");
    } else if (value.is_none()) {
        out << YAML::Null;
    } else if (py::isinstance<py::int_>(value) || py::isinstance<py::float_>(value) ||
               py::hasattr(value, "__index__") || py::hasattr(value, "__float__")) {
        // Numbers plainly (repr: Python's shortest text that reads back the same).
        const bool integral = py::hasattr(value, "__index__");
        const auto object = py::reinterpret_borrow<py::object>(value);
        const py::object number =
            integral ? py::object(py::int_(object)) : py::object(py::float_(object));
        out << py::repr(number).cast<std::string>();
    } else {
        const std::string s = py::str(value).cast<std::string>();
        if (std::regex_match(s, ratio))
            out << s; // a ratio (capture-set.md), plain
        else
            out << YAML::DoubleQuoted << s;
    }
}

} // namespace

CaptureManifest manifest_from_dict(py::handle dict, const fs::path& origin) {
    if (!py::isinstance<py::dict>(dict))
        throw py::type_error(origin.string() +
                             ": expected the manifest as a dict in "
                             "capture.yaml's layout, got " +
                             py::str(py::type::of(dict)).cast<std::string>());
    YAML::Emitter out;
    py_to_yaml(out, dict);
    return parse_manifest(out.c_str(), origin);
}

py::dict manifest_to_dict(const CaptureManifest& manifest) {
    return py::reinterpret_borrow<py::dict>(yaml_to_py(YAML::Load(manifest_to_yaml(manifest))));
}

namespace {

// The frames as a list (TypeError unless a sequence of arrays, with sequence= and projector=).
py::sequence frame_list(py::handle frames, py::handle sequence, py::handle projector) {
    if (!py::isinstance<py::sequence>(frames) || py::isinstance<py::str>(frames) ||
        py::isinstance<py::array>(frames))
        throw py::type_error("frames: expected a list of (H, W) uint8 or uint16 arrays, got " +
                             py::str(py::type::of(frames)).cast<std::string>());
    if (sequence.is_none() || projector.is_none())
        throw py::type_error("frames given without sequence= and projector=: the decoder needs "
                             "what the projector showed (capture.yaml's sequence list) and its "
                             "size (width, height)");
    return py::reinterpret_borrow<py::sequence>(frames);
}

// The manifest of `count` frames of size `camera` (1 x 1 without frames)
// shown `sequence` on `projector`.
CaptureManifest frames_manifest(std::size_t count, Size camera, py::handle sequence,
                                py::handle projector, int bit_depth, const fs::path& origin) {
    const Size proj = size_from(projector, "projector");
    py::dict m;
    m["format"] = kCaptureFormatV2;
    m["camera"] = py::dict(py::arg("width") = camera.width, py::arg("height") = camera.height);
    m["projector"] = py::dict(py::arg("width") = proj.width, py::arg("height") = proj.height);
    if (bit_depth != 0)
        m["bit_depth"] = bit_depth;
    py::list names;
    for (std::size_t i = 0; i < count; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "%03zu.png", i);
        names.append(name);
    }
    m["frames"] = names;
    m["sequence"] = sequence;
    return manifest_from_dict(m, origin / "capture.yaml");
}

std::string frame_name(std::size_t i) {
    return "frames[" + std::to_string(i) + "]";
}

} // namespace

CaptureSet capture_from_frames(py::handle frames, py::handle sequence, py::handle projector,
                               int bit_depth, const fs::path& origin) {
    const py::sequence list = frame_list(frames, sequence, projector);
    std::vector<Frame> images;
    images.reserve(list.size());
    for (std::size_t i = 0; i < list.size(); ++i)
        images.push_back(frame_from_array(list[i], frame_name(i)));
    const Size cam = images.empty() ? Size{1, 1} : images[0].size();
    CaptureManifest manifest =
        frames_manifest(images.size(), cam, sequence, projector, bit_depth, origin);
    py::gil_scoped_release release;
    return make_capture_set(origin, std::move(manifest), std::move(images));
}

CaptureView capture_view_from_frames(py::handle frames, py::handle sequence, py::handle projector,
                                     int bit_depth, const fs::path& origin, py::list& keep) {
    const py::sequence list = frame_list(frames, sequence, projector);
    std::vector<FrameView> views;
    views.reserve(list.size());
    for (std::size_t i = 0; i < list.size(); ++i)
        views.push_back(frame_view_from_array(list[i], frame_name(i), keep));
    const Size cam = views.empty() ? Size{1, 1} : views[0].size;
    CaptureManifest manifest =
        frames_manifest(views.size(), cam, sequence, projector, bit_depth, origin);
    py::gil_scoped_release release;
    return make_capture_view(origin, std::move(manifest), std::move(views));
}

// ---------------------------------------------------------------- bindings

namespace {

py::object truth_images(Capture& capture) {
    const auto& truth = capture.manifest().truth;
    if (!truth)
        return py::none();
    Image<float> xyz, projector;
    {
        py::gil_scoped_release release;
        if (!truth->xyz.empty())
            xyz = read_tiff_float(capture.folder() / truth->xyz);
        if (!truth->projector.empty())
            projector = read_tiff_float(capture.folder() / truth->projector);
    }
    py::dict d;
    d["xyz"] = take_array(std::move(xyz));
    d["projector"] = take_array(std::move(projector));
    return d;
}

void write_capture(const fs::path& folder, py::handle frames, py::handle manifest,
                   py::handle sequence, py::handle projector, int bit_depth, py::handle truth) {
    CaptureSet set;
    if (!manifest.is_none()) {
        if (!sequence.is_none() || !projector.is_none())
            throw py::type_error("write_capture: give manifest= or sequence= and projector=, "
                                 "not both");
        // The manifest's frame names and camera; the frames checked against it.
        CaptureManifest m = manifest_from_dict(manifest, folder / "capture.yaml");
        if (!py::isinstance<py::sequence>(frames) || py::isinstance<py::array>(frames))
            throw py::type_error("frames: expected a list of (H, W) uint8 or uint16 arrays");
        const auto list = py::reinterpret_borrow<py::sequence>(frames);
        std::vector<Frame> images;
        for (std::size_t i = 0; i < list.size(); ++i)
            images.push_back(frame_from_array(list[i], "frames[" + std::to_string(i) + "]"));
        set.manifest = std::move(m);
        set.frames = std::move(images);
    } else {
        set = capture_from_frames(frames, sequence, projector, bit_depth, folder);
    }
    Image<float> xyz, proj;
    TruthImages images;
    if (!truth.is_none()) {
        if (!py::isinstance<py::dict>(truth))
            throw py::type_error("truth: expected a dict with 'xyz' (H, W, 3) and/or "
                                 "'projector' (H, W, 2) float32 arrays");
        const auto t = py::reinterpret_borrow<py::dict>(truth);
        TruthFiles files;
        const Size cam = set.manifest.camera;
        if (t.contains("xyz") && !t["xyz"].is_none()) {
            xyz = float_image(t["xyz"], "truth['xyz']", 3, cam);
            images.xyz = &xyz;
            files.xyz = "truth_xyz.tiff";
        }
        if (t.contains("projector") && !t["projector"].is_none()) {
            proj = float_image(t["projector"], "truth['projector']", 2, cam);
            images.projector = &proj;
            files.projector = "truth_proj.tiff";
        }
        if (images.xyz || images.projector)
            set.manifest.truth = files;
    }
    py::gil_scoped_release release;
    write_capture_set(folder, set.manifest, set.frames, images);
}

// A frame file (PNG, TIFF, BMP: uint8 / uint16) or a float32 TIFF (1 to 4
// channels), as fpp reads them.
py::object read_image(const fs::path& path) {
    const std::string ext = path.extension().string();
    if (ext == ".tif" || ext == ".tiff") {
        Image<float> image;
        bool is_float = true;
        {
            py::gil_scoped_release release;
            try {
                image = read_tiff_float(path);
            } catch (const InputError&) { // not float32: a frame, or neither (said below)
                is_float = false;
            }
        }
        if (is_float)
            return take_array(std::move(image));
    }
    Frame frame;
    {
        py::gil_scoped_release release;
        frame = read_frame(path);
    }
    return frame.bit_depth == 8 ? take_array(std::move(frame.u8))
                                : take_array(std::move(frame.u16));
}

} // namespace

void bind_capture(py::module_& m) {
    py::class_<Capture, std::shared_ptr<Capture>>(
        m, "Capture",
        "A capture set (firmware/core/formats/capture-set.md): camera frames and the manifest\n"
        "that says what the projector showed for each.\n\n"
        "Made by fpp.read_capture(path) (the manifest read and checked at once, the frames\n"
        "on first use) or Capture.from_frames(...) (frames in memory). Pass it to\n"
        "fpp.decode: its frames are used where they are, without a copy.")
        .def_static(
            "from_frames",
            [](py::handle frames, py::handle sequence, py::handle projector, int bit_depth) {
                return std::make_shared<Capture>(
                    capture_from_frames(frames, sequence, projector, bit_depth, "<memory>"));
            },
            py::arg("frames"), py::arg("sequence"), py::arg("projector"), py::arg("bit_depth") = 0,
            "A capture set in memory (copied once into fpp's frames).\n\n"
            "frames: list of (H, W) uint8 or uint16 arrays, capture order (other dtypes:\n"
            "  TypeError; non-contiguous arrays are copied).\n"
            "sequence: capture.yaml's sequence, a list of block dicts, e.g.\n"
            "  [{'pattern': 'phase', 'axis': 'x', 'period': 20, 'steps': 8}, ...]\n"
            "  (capture.manifest['sequence'] of a set read from disk).\n"
            "projector: (width, height) in projector pixels.\n"
            "bit_depth: bits in use of 16-bit frames (9..16), 0 = found from the values.\n"
            "Raises fpp.InputError naming '<memory>/capture.yaml' and the field as the file\n"
            "reader does (e.g. 'frames: 3 frame images given for 22 listed frames').")
        .def_property_readonly(
            "path", [](const Capture& c) { return c.folder(); },
            "The capture's folder (pathlib.Path; '<memory>' for from_frames).")
        .def_property_readonly(
            "manifest", [](const Capture& c) { return manifest_to_dict(c.manifest()); },
            "capture.yaml as a dict (every field, as fpp writes it; a copy).")
        .def_property_readonly(
            "camera", [](const Capture& c) { return size_tuple(c.manifest().camera); },
            "Camera image size (width, height), pixels.")
        .def_property_readonly(
            "projector", [](const Capture& c) { return size_tuple(c.manifest().projector); },
            "Projector image size (width, height), pixels.")
        .def("__len__", [](const Capture& c) { return c.manifest().frames.size(); })
        .def_property_readonly(
            "loaded", &Capture::loaded,
            "Whether the frames have been read (reading .frames or decoding reads them).")
        .def_property_readonly(
            "frames",
            [](py::object self) {
                auto& c = self.cast<Capture&>();
                std::shared_ptr<const CaptureSet> set;
                {
                    py::gil_scoped_release release;
                    set = c.set();
                }
                py::tuple out(set->frames.size());
                for (std::size_t i = 0; i < set->frames.size(); ++i) {
                    const Frame& f = set->frames[i];
                    out[i] = f.bit_depth == 8 ? view_array(f.u8, self) : view_array(f.u16, self);
                }
                return out;
            },
            "The frames, capture order: a tuple of read-only (H, W) uint8 or uint16 arrays\n"
            "viewing the capture's memory (no copy). Read, all of them and checked, on first\n"
            "access (fpp.InputError naming the frame file and 'frames[i]').")
        .def_property_readonly(
            "bits_in_use",
            [](Capture& c) {
                py::gil_scoped_release release;
                return c.set()->bits_in_use;
            },
            "Bits in use of the frames (declared bit_depth, or found from the values; 8 for\n"
            "8-bit frames). Reads the frames.")
        .def_property_readonly("truth", &truth_images,
                               "Ground truth of a simulated set, or None: a dict with 'xyz'\n"
                               "((H, W, 3) float32, camera frame, mm, NaN = no surface) and\n"
                               "'projector' ((H, W, 2) float32, projector x, y per camera\n"
                               "pixel, pixel centres on integers), either None if not listed.")
        .def("__repr__", [](const Capture& c) {
            return "<fpp.Capture " + c.folder().string() + ": " +
                   std::to_string(c.manifest().frames.size()) + " frames, camera " +
                   std::to_string(c.manifest().camera.width) + "x" +
                   std::to_string(c.manifest().camera.height) + ">";
        });

    m.def(
        "read_capture",
        [](const fs::path& path) {
            py::gil_scoped_release release;
            return std::make_shared<Capture>(path);
        },
        py::arg("path"),
        "Reads a capture set folder (holding capture.yaml): fpp-capture/1 or /2.\n\n"
        "The manifest is read and checked now; the frames when first needed (.frames,\n"
        "fpp.decode). Returns an fpp.Capture. Raises fpp.InputError naming the file and\n"
        "the field for anything the format refuses (e.g. 'capture.yaml: sequence[2].steps:\n"
        "must be >= 3').");
    m.def("read_image", &read_image, py::arg("path"),
          "Reads an image as fpp reads its files: a grey frame (PNG, TIFF or BMP, 8- or\n"
          "16-bit: an (H, W) uint8 or uint16 array) or a float32 TIFF (fpp-calib decode's\n"
          "proj_x.tiff, a capture's truth: (H, W) or (H, W, C) float32). Raises\n"
          "fpp.InputError naming the file for anything else.");
    m.def("write_capture", &write_capture, py::arg("path"), py::arg("frames"), py::kw_only(),
          py::arg("manifest") = py::none(), py::arg("sequence") = py::none(),
          py::arg("projector") = py::none(), py::arg("bit_depth") = 0,
          py::arg("truth") = py::none(),
          "Writes a capture set folder atomically (it must not exist yet): 8- or 16-bit\n"
          "PNG frames and capture.yaml.\n\n"
          "frames: list of (H, W) uint8 or uint16 arrays.\n"
          "Either manifest= (a dict in capture.yaml's layout, e.g. another capture's\n"
          "  .manifest; its frame names are used) or sequence= (capture.yaml's list of\n"
          "  blocks) and projector=(width, height) (frames named 000.png, 001.png, ...).\n"
          "bit_depth: bits in use of 16-bit frames, 0 = not declared.\n"
          "truth: optional dict of 'xyz' ((H, W, 3) float32, camera frame, mm) and\n"
          "  'projector' ((H, W, 2) float32, projector px), written as truth TIFFs.\n"
          "Raises fpp.InputError (nothing written) naming the field, TypeError for arrays\n"
          "of the wrong dtype or shape.");
}

} // namespace fpp::python
