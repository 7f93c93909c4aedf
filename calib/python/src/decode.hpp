#pragma once
// fpp.decode and its result (fpp/decoder.hpp, fpp/decode_report.hpp).

#include "fpp/decode_consistency.hpp"
#include "fpp/decode_diagnosis.hpp"
#include "fpp/decode_report.hpp"
#include "fpp/decoder.hpp"

#include <pybind11/pybind11.h>

#include <memory>

namespace fpp::python {

namespace py = pybind11;

// A decode as Python sees it: the C++ result (its images viewed by the
// arrays, no copy) and the report's figures.
struct DecodeOutput {
    std::shared_ptr<const DecodeResult> result;
    DecodeStatistics stats;
    DecodeDiagnosis diagnosis;
    DecodeConsistency consistency;
    Size projector;
    double seconds = 0;
    py::object mask; // the valid pixels as booleans, made on first use
};

} // namespace fpp::python
