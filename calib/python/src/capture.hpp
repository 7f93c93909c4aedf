#pragma once
// Capture sets from Python (fpp/capture_set.hpp): fpp.read_capture,
// fpp.write_capture, fpp.Capture.

#include "fpp/capture_set.hpp"

#include <pybind11/pybind11.h>

#include <filesystem>
#include <memory>
#include <mutex>

namespace fpp::python {

namespace py = pybind11;

// A capture set as Python holds it: the manifest at once, the frames read on
// first need (all of them, checked as read_capture_set checks them) and kept.
class Capture {
public:
    // Read from a folder: the manifest now (validated), the frames later.
    explicit Capture(std::filesystem::path folder);
    // Held in memory (frames checked against the manifest now).
    explicit Capture(CaptureSet set);

    const std::filesystem::path& folder() const { return folder_; }
    const CaptureManifest& manifest() const { return manifest_; }
    bool loaded() const;
    // The whole set, its frames read on the first call (call without the
    // GIL: it reads files). Safe from several threads.
    std::shared_ptr<const CaptureSet> set();

private:
    std::filesystem::path folder_;
    CaptureManifest manifest_;
    mutable std::mutex mutex_;
    std::shared_ptr<const CaptureSet> set_;
};

// A manifest from a Python dict in capture.yaml's layout (the same checks and
// messages as the file's reader; `origin` names it in errors).
CaptureManifest manifest_from_dict(py::handle dict, const std::filesystem::path& origin);
// A manifest as a dict in capture.yaml's layout (every field, as the writer
// writes it).
py::dict manifest_to_dict(const CaptureManifest& manifest);

// Frames (a sequence of arrays), a sequence (capture.yaml's list of block
// dicts) and the projector's size as a capture set in memory; `origin` names
// it in errors.
CaptureSet capture_from_frames(py::handle frames, py::handle sequence, py::handle projector,
                               int bit_depth, const std::filesystem::path& origin);
// The same borrowing the frames (no sample copied where an array's rows are
// contiguous): the arrays viewed are appended to `keep`, which must outlive
// the view.
CaptureView capture_view_from_frames(py::handle frames, py::handle sequence, py::handle projector,
                                     int bit_depth, const std::filesystem::path& origin,
                                     py::list& keep);

} // namespace fpp::python
