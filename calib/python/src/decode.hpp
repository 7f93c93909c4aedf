#pragma once
// fpp.decode and its result (fpp/decoder.hpp, fpp/decode_report.hpp).

#include "fpp/decode_consistency.hpp"
#include "fpp/decode_diagnosis.hpp"
#include "fpp/decode_report.hpp"
#include "fpp/decoder.hpp"

#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>
#include <optional>

namespace fpp::python {

namespace py = pybind11;

// The report's figures of a decode (fpp-calib decode's decode.md).
struct DecodeReport {
    DecodeStatistics stats;
    DecodeDiagnosis diagnosis;
    DecodeConsistency consistency;
};

// The frames a decode reads, borrowed (no sample copied): a Capture's set or
// the caller's NumPy arrays, kept alive here while the result lives.
struct DecodeSource {
    CaptureView view;
    std::shared_ptr<const CaptureSet> set; // the frames' owner for an fpp.Capture
    py::object arrays;                     // the frames' owner for arrays (release with the GIL)
};

// A decode as Python sees it: the C++ result (its images viewed by the
// arrays, no copy) and the report, made when the decode is checked or on
// the first figure asked for.
struct DecodeOutput {
    std::shared_ptr<const DecodeResult> result;
    std::shared_ptr<const DecodeSource> capture; // for the report's diagnosis
    DecodeOptions options;
    Size projector;
    double seconds = 0;
    py::object mask; // the valid pixels as booleans, made on first use

    // Computes the report on the first call (call with the GIL released).
    const DecodeReport& report();

private:
    std::mutex mutex_;
    std::optional<DecodeReport> report_;
};

} // namespace fpp::python
