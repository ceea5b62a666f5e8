// The extension module pliant._pliant; the package pliant (python/pliant/__init__.py) re-exports
// it. Errors, threads and logging here; each area of the library in its own file.
#include <pybind11/functional.h>

#include <string>

#include "common.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/version.hpp"

namespace pliant::python {
namespace {

// Exception classes, created once at import; the translator below raises them.
PyObject* g_error = nullptr;
PyObject* g_invalid_input = nullptr;
PyObject* g_io_error = nullptr;
PyObject* g_unsupported = nullptr;
PyObject* g_internal_error = nullptr;
PyObject* g_interrupted = nullptr;

PyObject* new_exception(py::module_& m, const char* name, const char* doc, py::tuple bases) {
    const std::string qualified = std::string("pliant.") + name;
    PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
    if (type == nullptr) {
        throw py::error_already_set();
    }
    m.add_object(name, py::handle(type));  // the module holds a reference for the process
    return type;
}

}  // namespace

void bind_errors(py::module_& m) {
    g_error = new_exception(m, "Error", "Base class of every error pliant raises.",
                            py::make_tuple(py::handle(PyExc_Exception)));
    const py::handle error(g_error);
    g_invalid_input =
        new_exception(m, "InvalidInput",
                      "Arguments or data that break a documented precondition (also a ValueError).",
                      py::make_tuple(error, py::handle(PyExc_ValueError)));
    g_io_error = new_exception(
        m, "IoError", "A file that cannot be opened, read, parsed or written (also an OSError).",
        py::make_tuple(error, py::handle(PyExc_OSError)));
    g_unsupported = new_exception(
        m, "Unsupported", "A valid request pliant does not implement (also a NotImplementedError).",
        py::make_tuple(error, py::handle(PyExc_NotImplementedError)));
    g_internal_error = new_exception(m, "InternalError",
                                     "A broken invariant: a bug in pliant (also a RuntimeError).",
                                     py::make_tuple(error, py::handle(PyExc_RuntimeError)));
    g_interrupted = new_exception(m, "Interrupted",
                                  "A run stopped on request (Ctrl-C); what it wrote so far is "
                                  "consistent (a KeyboardInterrupt).",
                                  py::make_tuple(py::handle(PyExc_KeyboardInterrupt)));

    // Most derived first: the messages pass through unchanged. pybind11's translator signature
    // takes the exception_ptr by value.
    py::register_exception_translator([](std::exception_ptr p) {  // NOLINT(performance-*)
        try {
            if (p) {
                std::rethrow_exception(p);
            }
        } catch (const InvalidInput& e) {
            PyErr_SetString(g_invalid_input, e.what());
        } catch (const IoError& e) {
            PyErr_SetString(g_io_error, e.what());
        } catch (const Unsupported& e) {
            PyErr_SetString(g_unsupported, e.what());
        } catch (const InternalError& e) {
            PyErr_SetString(g_internal_error, e.what());
        } catch (const Error& e) {
            PyErr_SetString(g_error, e.what());
        } catch (const Interrupted& e) {
            PyErr_SetString(g_interrupted, e.what());
        }
    });
}

}  // namespace pliant::python

PYBIND11_MODULE(_pliant, m) {
    using namespace pliant;
    using namespace pliant::python;
    m.doc() =
        "pliant: cloth with fast self-collision and deformable volumes (the C++ library's "
        "bindings; import the package `pliant`).";
    m.attr("__version__") = PLIANT_VERSION;

    bind_errors(m);

    m.def("set_num_threads", &set_num_threads, py::arg("n"),
          "Limits every later parallel call to n threads (n >= 1), or to all hardware threads "
          "(n = 0). Results are bitwise identical for any n.");
    m.def("num_threads", &num_threads, "The current thread limit (>= 1).");
    m.def("hardware_threads", &hardware_threads, "Hardware threads available to this process.");

    m.def(
        "set_log_handler",
        [](const py::object& handler) {
            if (handler.is_none()) {
                set_log_sink({});
                return;
            }
            // The sink may be called from a thread that does not hold the GIL (a long call
            // releases it); the handler is released at interpreter exit (see __init__.py).
            auto shared = std::make_shared<py::object>(handler);
            set_log_sink([shared](LogLevel level, std::string_view message) {
                py::gil_scoped_acquire gil;
                try {
                    (*shared)(level_name(level), std::string(message));
                } catch (py::error_already_set& e) {
                    e.discard_as_unraisable("pliant log handler");
                }
            });
        },
        py::arg("handler"),
        "Routes the library's messages (start warnings of a cloth scene, untangling reports) to "
        "handler(level, message) with level one of 'debug', 'info', 'warning', 'error'; None "
        "restores the default (printed to stderr as 'pliant: <level>: <message>').");

    bind_mesh(m);
    bind_collision(m);
    bind_cloth(m);
    bind_volume(m);
    bind_render(m);
    bind_pbd(m);
    bind_nerf(m);
}
