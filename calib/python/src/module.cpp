// fpp._fpp: the compiled half of the Python package fpp (calib/python). The
// package's __init__.py re-exports it with the pure-Python parts.
#include "bindings.hpp"
#include "errors.hpp"

PYBIND11_MODULE(_fpp, m) {
    m.doc() = "fpp's compiled module (use the package: import fpp)";
    fpp::python::register_errors(m);
    fpp::python::bind_capture(m);
    fpp::python::bind_decode(m);
    fpp::python::bind_table(m);
    fpp::python::bind_ply(m);
    fpp::python::bind_stereo(m);
}
