// phri/core for Python: the error family as Python exceptions (same one-line messages), the
// version, the data directory, and the numpy views every other binding uses.
#include "bindings.hpp"

#include <phri/core/version.hpp>

#include <filesystem>

namespace phri::python {
namespace {

// The Python classes of the error family, created once at import and kept by the module.
struct ErrorClasses {
  PyObject* error = nullptr;
  PyObject* config = nullptr;
  PyObject* io = nullptr;
  PyObject* experiment = nullptr;
  PyObject* argument = nullptr;
  PyObject* missing_file = nullptr;
};
ErrorClasses errors;

PyObject* new_error_class(py::module_& m, const char* name, py::handle bases, const char* doc) {
  const std::string qualified = std::string("phri.") + name;
  PyObject* cls = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (cls == nullptr) throw py::error_already_set();
  m.add_object(name, py::handle(cls));  // the module holds the reference for the process's life
  return cls;
}

// Raises `cls(message)` with the given attributes: str(exception) is the C++ what(), unchanged.
void raise(PyObject* cls, const char* message, std::initializer_list<std::pair<const char*, std::string>> attributes) {
  py::object exception = py::reinterpret_borrow<py::object>(cls)(message);
  for (const auto& [name, value] : attributes) exception.attr(name) = value;
  PyErr_SetObject(cls, exception.ptr());
}

void translate(std::exception_ptr p) {
  try {
    if (p) std::rethrow_exception(p);
  } catch (const ConfigError& e) {
    // A file that is not there is also Python's FileNotFoundError (an OSError); str(e) stays the
    // C++ message (OSError's filename is left unset: it would replace the message in str(e)).
    const bool missing = !e.file().empty() && e.file().front() != '<' && !std::filesystem::exists(e.file());
    raise(missing ? errors.missing_file : errors.config, e.what(),
          {{"file", e.file()}, {"element", e.element()}, {"reason", e.reason()}});
  } catch (const IoError& e) {
    raise(errors.io, e.what(), {{"path", e.path()}});
  } catch (const ExperimentError& e) {
    raise(errors.experiment, e.what(), {{"subject", e.subject()}});
  } catch (const ArgumentError& e) {
    raise(errors.argument, e.what(), {});
  } catch (const Error& e) {
    raise(errors.error, e.what(), {});
  }
}

void bind_errors(py::module_& m) {
  errors.error = new_error_class(m, "Error", PyExc_RuntimeError,
                                 "Any phri failure (C++ phri::Error); str(e) is the C++ one-line message.");
  const py::handle base(errors.error);
  errors.config = new_error_class(m, "ConfigError", base,
                                  "A file, key or argument is wrong; attributes file, element, reason.");
  errors.io = new_error_class(m, "IoError", base, "A file or directory cannot be read or written; attribute path.");
  errors.experiment = new_error_class(m, "ExperimentError", base,
                                      "An experiment ran but could not produce its result; attribute subject.");
  errors.argument = new_error_class(m, "ArgumentError", py::make_tuple(base, py::handle(PyExc_ValueError)),
                                    "A vector or matrix of the wrong size or a bad value was handed to phri.");
  errors.missing_file = new_error_class(m, "MissingFileError", py::make_tuple(py::handle(errors.config), py::handle(PyExc_FileNotFoundError)),
                                        "A file phri was given is not there: a ConfigError and a FileNotFoundError; attribute file.");
  py::register_exception_translator(&translate);
}

}  // namespace

std::string& data_dir() {
  static std::string dir;
  return dir;
}

std::string locate(const std::string& relative) {
  if (relative.empty() || std::filesystem::path(relative).is_absolute() || std::filesystem::exists(relative) ||
      data_dir().empty()) {
    return relative;
  }
  return (std::filesystem::path(data_dir()) / relative).string();
}

// numpy flags, as pybind11's own Eigen views clear them: the array stays a view, only read-only.
void make_read_only(py::array& a) {
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
}

py::array_t<double> matrix_view(const Eigen::MatrixXd& matrix, py::handle owner, bool writeable) {
  const auto size = static_cast<py::ssize_t>(sizeof(double));
  py::array_t<double> a({matrix.rows(), matrix.cols()}, {size, size * matrix.rows()}, matrix.data(), owner);
  if (!writeable) make_read_only(a);
  return a;
}

py::array_t<double> vector_view(const double* data, long size, py::handle owner, bool writeable) {
  py::array_t<double> a({size}, {static_cast<py::ssize_t>(sizeof(double))}, data, owner);
  if (!writeable) make_read_only(a);
  return a;
}

py::array_t<double> vector_view(const Eigen::VectorXd& vector, py::handle owner, bool writeable) {
  return vector_view(vector.data(), static_cast<long>(vector.size()), owner, writeable);
}

py::array_t<double> isometry_view(const Eigen::Isometry3d& pose, py::handle owner) {
  const auto size = static_cast<py::ssize_t>(sizeof(double));
  py::array_t<double> a({4, 4}, {size, 4 * size}, pose.matrix().data(), owner);
  make_read_only(a);
  return a;
}

void assign_same_size(Eigen::VectorXd& target, const Eigen::Ref<const Eigen::VectorXd>& values, const char* what) {
  check_size(what, "the new value", static_cast<long>(values.size()), static_cast<long>(target.size()));
  target = values;
}

void check_index(const char* function, long index, long count) {
  if (index < 0 || index >= count) {
    throw ArgumentError(std::string(function) + ": index " + std::to_string(index) + " out of range [0, " +
                        std::to_string(count) + ")");
  }
}

void bind_core(py::module_& m) {
  bind_errors(m);
  m.def("version", &phri::version, "The phri library's version, e.g. '0.1.0'.");
  m.def("_set_data_dir", [](const std::string& dir) { data_dir() = dir; },
        "Sets where relative robot, configuration and script names are found (phri/__init__.py does it).");
  m.def("data_dir", []() { return data_dir(); },
        "Folder of the robot files (robots/), configurations (configs/) and report scripts (tools/report/).");
  m.def("locate", &locate, py::arg("relative"),
        "The path itself when it exists from the working directory (or is absolute), else the same name in data_dir().");
}

}  // namespace phri::python
