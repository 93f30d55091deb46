#pragma once
// Shared pieces of the phri Python module (_phri): one bind_<module>() per phri module, the views
// that hand C++ buffers to numpy without copying, and the enum helper that gives every enumeration
// the names users already see in configurations and logs.
#include <phri/core/error.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>  // str or any os.PathLike where a path is taken

#include <array>
#include <string>
#include <string_view>

namespace phri::python {

namespace py = pybind11;

void bind_core(py::module_& m);
void bind_model(py::module_& m);
void bind_robot(py::module_& m);
void bind_sim(py::module_& m);
void bind_control(py::module_& m);
void bind_app(py::module_& m);
void bind_closed_loop(py::module_& m);
void bind_log(py::module_& m);
void bind_experiments(py::module_& m);

/// Where the package found the robot files, configurations and report scripts (set by
/// phri/__init__.py at import). Relative names that do not exist from the working directory are
/// looked up there, as the `phri` command does with its source tree.
std::string& data_dir();
std::string locate(const std::string& relative);

/// Clears numpy's writeable flag of `a` (still a view).
void make_read_only(py::array& a);
/// A numpy view of a column-major matrix or vector owned by `owner` (which the view keeps alive).
/// Read-only unless `writeable`; it sees every later change of the C++ buffer.
py::array_t<double> matrix_view(const Eigen::MatrixXd& matrix, py::handle owner, bool writeable = false);
py::array_t<double> vector_view(const Eigen::VectorXd& vector, py::handle owner, bool writeable = false);
py::array_t<double> vector_view(const double* data, long size, py::handle owner, bool writeable = false);
/// A 4 x 4 homogeneous view of an isometry (Eigen stores it as a column-major 4 x 4 matrix).
py::array_t<double> isometry_view(const Eigen::Isometry3d& pose, py::handle owner);

/// Copies `values` into `target` without resizing it; ArgumentError naming `what` on a size mismatch.
void assign_same_size(Eigen::VectorXd& target, const Eigen::Ref<const Eigen::VectorXd>& values, const char* what);

/// ArgumentError "function: index i out of range [0, count)" unless 0 <= i < count.
void check_index(const char* function, long index, long count);

/// Binds an enumeration whose values are 0 .. Count - 1 with the names of its to_string().
template <class Enum, int Count>
py::enum_<Enum> bind_enum(py::handle scope, const char* name, const char* doc) {
  py::enum_<Enum> e(scope, name, doc);
  for (int i = 0; i < Count; ++i) {
    const auto value = static_cast<Enum>(i);
    const std::string_view label = to_string(value);
    e.value(std::string(label).c_str(), value);
  }
  return e;
}

}  // namespace phri::python

// Eigen::Isometry3d <-> a 4 x 4 homogeneous numpy array (a copy each way). The bottom row must be
// [0, 0, 0, 1] and the rotation orthonormal within 1e-6 (an Isometry is nothing else).
namespace pybind11::detail {
template <>
struct type_caster<Eigen::Isometry3d> {
  PYBIND11_TYPE_CASTER(Eigen::Isometry3d, const_name("numpy.ndarray[numpy.float64[4, 4]]"));

  bool load(handle source, bool convert) {
    if (!convert && !isinstance<array_t<double>>(source)) return false;
    auto a = array_t<double, array::c_style | array::forcecast>::ensure(source);
    if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) return false;
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) m(r, c) = a.at(r, c);
    }
    const bool bottom = (m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() <= 1e-12;
    const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
    if (!bottom || (r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > 1e-6) {
      throw phri::ArgumentError("a pose must be a 4 x 4 homogeneous transform: orthonormal rotation, bottom row [0, 0, 0, 1]");
    }
    value.matrix() = m;
    return true;
  }

  static handle cast(const Eigen::Isometry3d& pose, return_value_policy, handle) {
    array_t<double> a({4, 4});
    auto w = a.mutable_unchecked<2>();
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) w(r, c) = pose.matrix()(r, c);
    }
    return a.release();
  }
};
}  // namespace pybind11::detail
