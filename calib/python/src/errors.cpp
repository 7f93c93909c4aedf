#include "errors.hpp"

#include "fpp/error.hpp"

namespace fpp::python {

namespace {

// Created once, by register_errors (the module's initialisation), and kept
// for the life of the process as CPython keeps extension modules.
PyObject* input_error_type = nullptr;
PyObject* decode_error_type = nullptr;

PyObject* new_exception_type(py::module_& m, const char* name, PyObject* base, const char* doc) {
    const std::string qualified = std::string("fpp.") + name;
    PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, base, nullptr);
    if (!type)
        throw py::error_already_set();
    m.add_object(name, py::handle(type));
    return type;
}

} // namespace

void register_errors(py::module_& m) {
    input_error_type = new_exception_type(
        m, "InputError", PyExc_ValueError,
        "Bad input, as fpp's C++ code refuses it: a file or an argument that cannot be used.\n\n"
        "A ValueError. str(e) is 'FILE: FIELD: what is wrong'; the attributes `file` (the\n"
        "file, or the function or argument list, named) and `field` (the field or option\n"
        "in it, e.g. 'sequence[2].period', 'min_modulation') say what to fix.");
    decode_error_type = new_exception_type(
        m, "DecodeError", PyExc_RuntimeError,
        "A decode that failed (nearly nothing decoded, or the capture's description is\n"
        "evidently wrong: reason 'failed') or whose field is inconsistent with itself\n"
        "(reason 'inconsistent', unless accept_inconsistent=True), as fpp-calib decode\n"
        "exits 3 or 5. str(e) names the likely cause; `result` holds the DecodeResult for\n"
        "inspection and `reason` is 'failed' or 'inconsistent'.");
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p)
                std::rethrow_exception(p);
        } catch (const InputError& e) {
            py::object error = py::reinterpret_borrow<py::object>(input_error_type)(e.what());
            error.attr("file") = e.file().string();
            error.attr("field") = e.field();
            PyErr_SetObject(input_error_type, error.ptr());
        } catch (const IoError& e) {
            PyErr_SetString(PyExc_OSError, e.what());
        }
    });
}

void raise_decode_error(const std::string& message, const std::string& reason, py::object result) {
    py::object error = py::reinterpret_borrow<py::object>(decode_error_type)(message);
    error.attr("result") = std::move(result);
    error.attr("reason") = reason;
    PyErr_SetObject(decode_error_type, error.ptr());
    throw py::error_already_set();
}

} // namespace fpp::python
