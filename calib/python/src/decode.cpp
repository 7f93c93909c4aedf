#include "decode.hpp"

#include "arrays.hpp"
#include "bindings.hpp"
#include "capture.hpp"
#include "errors.hpp"

#include "fpp/calib/decode_options.hpp"

#include <pybind11/stl.h>

#include <chrono>
#include <vector>

namespace fpp::python {

const DecodeReport& DecodeOutput::report() {
    const std::lock_guard lock(mutex_);
    if (!report_) {
        DecodeReport r;
        r.stats = decode_statistics(*result, frames_full_scale(capture->view));
        r.diagnosis = diagnose_decode(capture->view, *result, r.stats, options);
        r.consistency = check_decode_consistency(*result, capture->view.manifest.sequence);
        report_ = std::move(r);
    }
    return *report_;
}

namespace {

// A figure of the report (made on first use, without the GIL).
template <class Get> auto figure(Get get) {
    return [get](DecodeOutput& out) {
        const DecodeReport* report;
        {
            py::gil_scoped_release release;
            report = &out.report();
        }
        return get(*report);
    };
}

// The capture a decode reads, its frames borrowed: fpp.Capture's (read on
// first use and kept by it), or the arrays given with a sequence (viewed in
// place where their rows are contiguous, else copied contiguous once).
std::shared_ptr<const DecodeSource> capture_of(py::handle source, py::handle sequence,
                                               py::handle projector, int bit_depth) {
    auto made = std::make_shared<DecodeSource>();
    if (py::isinstance<Capture>(source)) {
        if (!sequence.is_none() || !projector.is_none())
            throw py::type_error("decode: a Capture carries its own sequence and projector; "
                                 "give sequence= and projector= only with frames");
        auto& capture = source.cast<Capture&>();
        py::gil_scoped_release release;
        made->set = capture.set();
        made->view = view_of(*made->set);
        return made;
    }
    py::list keep;
    made->view =
        capture_view_from_frames(source, sequence, projector, bit_depth, "fpp.decode", keep);
    made->arrays = std::move(keep);
    return made;
}

py::object decode(py::handle source, py::handle sequence, py::handle projector, int bit_depth,
                  double min_modulation, int threads, bool correct_phase_error,
                  bool accept_inconsistent, bool check) {
    DecodeOptions options;
    options.min_modulation = min_modulation;
    options.threads = threads;
    options.correct_phase_error = correct_phase_error;
    calib::check_decode_options(options, calib::OptionSpelling::keyword, "fpp.decode");
    const std::shared_ptr<const DecodeSource> capture =
        capture_of(source, sequence, projector, bit_depth);

    auto out = std::make_shared<DecodeOutput>();
    {
        py::gil_scoped_release release;
        const auto start = std::chrono::steady_clock::now();
        out->result = std::make_shared<const DecodeResult>(fpp::decode(capture->view, options));
        out->seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        out->capture = capture;
        out->options = options;
        out->projector = capture->view.manifest.projector;
        if (check)
            out->report();
    }
    py::object made = py::cast(out);
    if (!check)
        return made;
    const DecodeReport& report = out->report();
    const std::string where = capture->view.folder.string();
    if (report.diagnosis.failed)
        raise_decode_error(where + ": " + report.diagnosis.message, "failed", made);
    if (report.consistency.inconsistent && !accept_inconsistent)
        raise_decode_error(where + ": the decode is inconsistent: " + report.consistency.message +
                               " (accept_inconsistent=True to take the field as it is)",
                           "inconsistent", made);
    return made;
}

// The C++ work of decode() alone, timed (tests/bench/bench_python_decode.py's
// baseline, in the same process on the same frames): fpp::decode, and with
// `report` the statistics, diagnosis and consistency check decode() adds;
// no Python object is made. Seconds of each of `repeats` runs.
std::vector<double> cpp_decode_seconds(Capture& capture, int repeats, int threads, bool report) {
    DecodeOptions options;
    options.threads = threads;
    std::vector<double> seconds;
    py::gil_scoped_release release;
    const std::shared_ptr<const CaptureSet> set = capture.set();
    for (int i = 0; i < repeats; ++i) {
        const auto start = std::chrono::steady_clock::now();
        const DecodeResult result = fpp::decode(*set, options);
        if (report) {
            const DecodeStatistics stats = decode_statistics(result, frames_full_scale(*set));
            const DecodeDiagnosis diagnosis = diagnose_decode(*set, result, stats, options);
            const DecodeConsistency consistency =
                check_decode_consistency(result, set->manifest.sequence);
            if (diagnosis.failed && consistency.inconsistent)
                seconds.push_back(-1); // never: keeps the work from being dropped
        }
        seconds.push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    return seconds;
}

template <class Get> auto image_property(Get get) {
    return [get](py::object self) {
        const auto& out = self.cast<const DecodeOutput&>();
        return view_array(get(*out.result), self);
    };
}

py::dict phase_correction(const PhaseErrorSummary& s) {
    py::dict d;
    d["attempted"] = s.attempted;
    d["applied"] = s.applied;
    d["reason"] = s.reason;
    return d;
}

} // namespace

void bind_decode(py::module_& m) {
    py::class_<DecodeOutput, std::shared_ptr<DecodeOutput>>(
        m, "DecodeResult",
        "What fpp.decode returns: per camera pixel arrays (read-only views of the C++\n"
        "result, no copy) and the report's figures (fpp-calib decode's decode.md).\n\n"
        "Arrays, camera height x width:\n"
        "  proj_x, proj_y  float32, projector x (column) and y (row) in projector pixels,\n"
        "                  pixel centres on integers; NaN where not decoded; None when the\n"
        "                  sequence codes no such axis\n"
        "  modulation      float32, fringe modulation B of the finest phase block, camera DN\n"
        "  mean            float32, its mean intensity A, camera DN\n"
        "  mask            bool, True where the pixel decoded (flags & 1)\n"
        "  flags           uint8, per-pixel bits: 1 valid, 2 low modulation, 4 saturated,\n"
        "                  8 unwrapping inconsistent, 16 no absolute cue, 32 out of the\n"
        "                  projector")
        .def_property_readonly(
            "proj_x", image_property([](const DecodeResult& r) -> auto& { return r.proj_x; }),
            "Projector x per camera pixel (float32, projector px, NaN invalid).")
        .def_property_readonly(
            "proj_y", image_property([](const DecodeResult& r) -> auto& { return r.proj_y; }),
            "Projector y per camera pixel (float32, projector px, NaN "
            "invalid), or None.")
        .def_property_readonly("modulation", image_property([](const DecodeResult& r) -> auto& {
                                   return r.modulation;
                               }),
                               "Fringe modulation B (float32, camera DN).")
        .def_property_readonly(
            "mean", image_property([](const DecodeResult& r) -> auto& { return r.mean; }),
            "Mean intensity A (float32, camera DN).")
        .def_property_readonly(
            "flags", image_property([](const DecodeResult& r) -> auto& { return r.mask; }),
            "DecodeFlag bits per pixel (uint8; see the class's help).")
        .def_property_readonly(
            "mask",
            [](py::object self) {
                auto& out = self.cast<DecodeOutput&>();
                if (!out.mask) {
                    py::object flags = view_array(out.result->mask, self);
                    out.mask = (flags & py::int_(int(kDecodeValid))).attr("astype")("bool");
                    out.mask.attr("flags").attr("writeable") = false;
                }
                return out.mask;
            },
            "True where the pixel decoded (bool, camera height x width).")
        .def_property_readonly(
            "camera", [](const DecodeOutput& o) { return size_tuple(o.result->camera); },
            "Camera image size (width, height).")
        .def_property_readonly(
            "projector", [](const DecodeOutput& o) { return size_tuple(o.projector); },
            "Projector image size (width, height).")
        .def_property_readonly(
            "method_x", [](const DecodeOutput& o) { return o.result->method_x; },
            "How x was unwrapped, e.g. 'complementary-gray' ('' if not coded).")
        .def_property_readonly(
            "method_y", [](const DecodeOutput& o) { return o.result->method_y; },
            "How y was unwrapped ('' if not coded).")
        .def_readonly("seconds", &DecodeOutput::seconds, "The decode's own time, s.")
        .def_property_readonly("pixels",
                               figure([](const DecodeReport& o) { return o.stats.pixels; }),
                               "Camera pixels.")
        .def_property_readonly(
            "lit", figure([](const DecodeReport& o) { return o.stats.lit; }),
            "Lit pixels: modulation at or above lit_floor, saturated, or decoded.")
        .def_property_readonly("decoded",
                               figure([](const DecodeReport& o) { return o.stats.decoded; }),
                               "Decoded pixels.")
        .def_property_readonly("coverage_of_lit", figure([](const DecodeReport& o) {
                                   return o.stats.coverage_of_lit();
                               }),
                               "decoded / lit (0..1).")
        .def_property_readonly("lit_floor",
                               figure([](const DecodeReport& o) { return o.stats.lit_floor; }),
                               "Modulation (camera DN) at or above which a pixel is lit.")
        .def_property_readonly("full_scale",
                               figure([](const DecodeReport& o) { return o.stats.full_scale; }),
                               "The frames' full scale, DN (255, 4095, 65535).")
        .def_property_readonly("floor_rule",
                               figure([](const DecodeReport& o) { return o.stats.floor_rule(); }),
                               "How the lit floor was found (one line).")
        .def_property_readonly(
            "dropped", figure([](const DecodeReport& o) {
                py::dict d;
                d["dark"] = o.stats.dark;
                d["saturated"] = o.stats.saturated;
                d["low_modulation"] = o.stats.low_modulation;
                d["unwrap_inconsistent"] = o.stats.unwrap_inconsistent;
                d["out_of_range"] = o.stats.out_of_range;
                d["no_cue"] = o.stats.no_cue;
                d["other"] = o.stats.other;
                return d;
            }),
            "Pixels not decoded, by reason, each counted once in this order: dark,\n"
            "saturated, low_modulation, unwrap_inconsistent, out_of_range, no_cue, other.")
        .def_property_readonly(
            "diagnosis", figure([](const DecodeReport& o) { return o.diagnosis.message; }),
            "The likely cause when little decoded or the description looks wrong ('' when\n"
            "the decode is not suspect).")
        .def_property_readonly("failed",
                               figure([](const DecodeReport& o) { return o.diagnosis.failed; }),
                               "Whether the decode failed (fpp-calib decode's exit 3).")
        .def_property_readonly(
            "inconsistent",
            figure([](const DecodeReport& o) { return o.consistency.inconsistent; }),
            "Whether the field is inconsistent with itself (fpp-calib decode's exit 5).")
        .def_property_readonly(
            "consistency", figure([](const DecodeReport& o) { return o.consistency.message; }),
            "What the consistency check measured and the field to check ('' when consistent).")
        .def_property_readonly(
            "phase_correction_x",
            [](const DecodeOutput& o) { return phase_correction(o.result->phase_correction_x); },
            "The data-only phase-error correction of x (correct_phase_error=True).")
        .def_property_readonly(
            "phase_correction_y",
            [](const DecodeOutput& o) { return phase_correction(o.result->phase_correction_y); },
            "The same for y.")
        .def("__repr__", [](const DecodeOutput& o) {
            std::size_t decoded = 0;
            for (const std::uint8_t f : o.result->mask.storage())
                decoded += (f & kDecodeValid) ? 1 : 0;
            return "<fpp.DecodeResult " + std::to_string(o.result->camera.width) + "x" +
                   std::to_string(o.result->camera.height) + " " + o.result->method_x +
                   (o.result->method_y.empty() ? "" : " / " + o.result->method_y) + ": " +
                   std::to_string(decoded) + " pixels decoded>";
        });

    m.def("_cpp_decode_seconds", &cpp_decode_seconds, py::arg("capture"), py::arg("repeats"),
          py::arg("threads") = 0, py::arg("report") = true,
          "Benchmark baseline: the C++ decode of `capture` timed `repeats` times (s each).");
    m.def("decode", &decode, py::arg("capture"), py::arg("sequence") = py::none(), py::kw_only(),
          py::arg("projector") = py::none(), py::arg("bit_depth") = 0,
          py::arg("min_modulation") = 0.02, py::arg("threads") = 0,
          py::arg("correct_phase_error") = false, py::arg("accept_inconsistent") = false,
          py::arg("check") = true,
          R"(Decodes a capture into projector coordinates per camera pixel (fpp-calib decode).

capture: an fpp.Capture (fpp.read_capture, Capture.from_frames; its frames are
  used in place), or a list of (H, W) uint8 / uint16 frames, capture order,
  with sequence= (capture.yaml's list of block dicts) and projector=(width,
  height), read in place, not copied (a frame whose rows are not contiguous
  is copied contiguous first); the result keeps them alive, and they must not
  change while decoding. The unwrapping method follows from the sequence.
bit_depth: with frames, bits in use of 16-bit frames (0 = found from the values).
min_modulation: a pixel needs a modulation of at least this fraction of full
  scale (fpp-calib decode --min-modulation), in [0, 1).
threads: worker threads, 0 = all cores (--threads).
correct_phase_error: remove the periodic phase error of a non-linear response
  from the capture alone (--correct-phase-error).
accept_inconsistent: return a field that is inconsistent with itself rather
  than raise (--accept-inconsistent).
check: judge the decode as fpp-calib decode does (the report's statistics,
  diagnosis and consistency check; DecodeError below) before returning. False
  returns the arrays alone, at the C++ decoder's own speed (the report is
  then made when a figure is first read; at 1600 x 1200 it costs several
  times the decode itself).

Returns an fpp.DecodeResult: proj_x, proj_y (projector px, pixel centres on
integers, NaN invalid), modulation, mean, mask, flags, and the report's
figures (lit, decoded, coverage_of_lit, dropped, diagnosis, ...).
Raises fpp.InputError for bad input (a bad option names it: 'fpp.decode:
min_modulation: must be in [0, 1), got ...'; a bad sequence or frame names
capture.yaml and the field), TypeError for frames of the wrong dtype or shape,
fpp.DecodeError (with .result) when nearly nothing decoded or the capture's
description is evidently wrong, or the field is inconsistent with itself.
The GIL is released while decoding.)");
}

} // namespace fpp::python
