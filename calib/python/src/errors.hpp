#pragma once
// fpp's C++ errors as Python exceptions:
//   fpp::InputError (and its subclasses) -> fpp.InputError, a ValueError
//     subclass whose `file` and `field` name what to fix
//   fpp::IoError                         -> OSError
//   std::invalid_argument                -> ValueError (pybind11's own)
// and fpp.DecodeError (a RuntimeError): a decode that failed or is
// inconsistent with itself, carrying the result (`result`) and `reason`.

#include <pybind11/pybind11.h>

#include <string>

namespace fpp::python {

namespace py = pybind11;

void register_errors(py::module_& m);

// Raises fpp.DecodeError(message) with `result` and `reason` ("failed" or
// "inconsistent") set; throws py::error_already_set.
[[noreturn]] void raise_decode_error(const std::string& message, const std::string& reason,
                                     py::object result);

} // namespace fpp::python
