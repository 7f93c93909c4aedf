#pragma once
// The module's areas, each binding its part of fpp (module.cpp calls them in order).

#include <pybind11/pybind11.h>

namespace fpp::python {

namespace py = pybind11;

void bind_capture(py::module_& m); // capture.cpp
void bind_decode(py::module_& m);  // decode.cpp
void bind_table(py::module_& m);   // table.cpp
void bind_ply(py::module_& m);     // ply.cpp
void bind_stereo(py::module_& m);  // stereo.cpp

} // namespace fpp::python
