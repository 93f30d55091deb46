// phri/model for Python: Model (from URDF), Data and the rigid-body algorithms, Pinocchio style:
//   model = phri.Model.from_urdf_file(path); data = phri.Data(model)
//   M = phri.crba(model, data, q)       # a read-only view of data.mass_matrix, no copy
// Inputs (q, qd, qdd: 7 numbers) are copied into Eigen vectors; results are views of Data's
// buffers, which the next call overwrites (copy them to keep them).
#include "bindings.hpp"

#include <phri/model/algorithms.hpp>

#include <cmath>
#include <optional>
#include <string>

namespace phri::python {
namespace {

using Vector = Eigen::VectorXd;

// The Python object of a Data the caller passed in (pybind11 finds the existing wrapper), to own a view.
py::object owner_of(const Data& data) { return py::cast(&data, py::return_value_policy::reference); }

// A read-only view of one of Data's vectors, owned by the Data.
py::array_t<double> data_vector(const Data& data, const Eigen::VectorXd& vector) { return vector_view(vector, owner_of(data)); }

void bind_model_types(py::module_& m) {
  py::enum_<JointType>(m, "JointType", "Joint kinds a URDF chain may have.")
      .value("revolute", JointType::kRevolute)
      .value("continuous", JointType::kContinuous)
      .value("prismatic", JointType::kPrismatic);
  py::enum_<FrameType>(m, "FrameType", "A link's own frame or one added by ModelOptions.extra_frames.")
      .value("link", FrameType::kLink)
      .value("extra", FrameType::kExtra);
  py::enum_<ReferenceFrame>(m, "ReferenceFrame", "Frame of expression of a frame's velocity, acceleration or Jacobian.")
      .value("world", ReferenceFrame::kWorld, "velocity of the point at the world origin, world axes")
      .value("local_world_aligned", ReferenceFrame::kLocalWorldAligned, "velocity of the frame origin, world axes")
      .value("local", ReferenceFrame::kLocal, "velocity of the frame origin, frame axes");

  py::class_<Inertia>(m, "Inertia", "Mass [kg], centre of mass [m] and inertia about it [kg m^2], in the owning frame.")
      .def(py::init<>())
      .def_readwrite("mass", &Inertia::mass)
      .def_readwrite("com", &Inertia::com)
      .def_readwrite("inertia_com", &Inertia::inertia_com);
  py::class_<Joint>(m, "Joint", "One joint of the chain (a copy of the model's).")
      .def_readonly("name", &Joint::name)
      .def_readonly("type", &Joint::type)
      .def_readonly("axis", &Joint::axis)
      .def_readonly("placement", &Joint::placement, "Joint frame in the parent body frame at q = 0 (4 x 4).")
      .def_readonly("lower", &Joint::lower)
      .def_readonly("upper", &Joint::upper)
      .def_readonly("velocity_limit", &Joint::velocity_limit)
      .def_readonly("effort_limit", &Joint::effort_limit)
      .def_readonly("armature", &Joint::armature)
      .def("has_position_limits", &Joint::has_position_limits, "False for a continuous joint.")
      .def("__repr__", [](const Joint& j) { return "<phri.Joint '" + j.name + "'>"; });
  py::class_<Frame>(m, "Frame", "A named frame fixed to a body (a copy of the model's).")
      .def_readonly("name", &Frame::name)
      .def_readonly("type", &Frame::type)
      .def_readonly("body", &Frame::body, "Body index; -1 for the base.")
      .def_readonly("placement", &Frame::placement, "In the body frame (4 x 4).")
      .def("__repr__", [](const Frame& f) { return "<phri.Frame '" + f.name + "'>"; });
  py::class_<ExtraFrame>(m, "ExtraFrame", "A frame to add to the model, fixed to an existing frame.")
      .def(py::init([](std::string name, std::string parent, const Eigen::Isometry3d& placement) {
             return ExtraFrame{std::move(name), std::move(parent), placement};
           }),
           py::arg("name"), py::arg("parent_frame"), py::arg("placement") = Eigen::Isometry3d::Identity())
      .def_readwrite("name", &ExtraFrame::name)
      .def_readwrite("parent_frame", &ExtraFrame::parent_frame)
      .def_readwrite("placement", &ExtraFrame::placement);
  py::class_<Payload>(m, "Payload", "A rigid payload (tool, sensor) merged into the body of `frame`.")
      .def(py::init<>())
      .def_readwrite("name", &Payload::name)
      .def_readwrite("frame", &Payload::frame)
      .def_readwrite("inertia", &Payload::inertia);
}

void bind_model_options(py::module_& m) {
  py::class_<ModelOptions>(m, "ModelOptions", "How a URDF becomes a Model: base and tip, locked joints, frames, payloads.")
      .def(py::init<>())
      .def_readwrite("base_link", &ModelOptions::base_link, "Empty: the URDF root link.")
      .def_readwrite("tip_link", &ModelOptions::tip_link, "Empty: the end of the chain of movable joints.")
      .def_readwrite("locked_joints", &ModelOptions::locked_joints, "Joints off the chain treated as fixed at 0.")
      .def_readwrite("extra_frames", &ModelOptions::extra_frames)
      .def_readwrite("payloads", &ModelOptions::payloads)
      .def_readwrite("armature", &ModelOptions::armature, "Reflected rotor inertia per joint [kg m^2] (empty: none).")
      .def_readwrite("gravity", &ModelOptions::gravity, "In the world frame [m/s^2].")
      .def_readwrite("base_placement", &ModelOptions::base_placement, "Base link in the world (4 x 4).");
}

void bind_model_class(py::module_& m) {
  py::class_<Model>(m, "Model", "A serial arm loaded from a URDF; immutable (algorithms write into a Data).")
      .def_static("from_urdf_file",
                  [](const std::filesystem::path& path, const ModelOptions& options) { return Model::from_urdf_file(path.string(), options); },
                  py::arg("path"), py::arg("options") = ModelOptions{},
                  "Loads a URDF file; ConfigError naming the file and the element on bad input.")
      .def_static("from_urdf_string", &Model::from_urdf_string, py::arg("urdf"), py::arg("options") = ModelOptions{},
                  py::arg("source_name") = "<urdf string>", "Loads a URDF from text; source_name stands for it in errors.")
      .def_property_readonly("name", &Model::name)
      .def_property_readonly("nq", &Model::nq)
      .def_property_readonly("nv", &Model::nv)
      .def_property_readonly("num_bodies", &Model::num_bodies)
      .def_property_readonly("num_frames", &Model::num_frames)
      .def_property_readonly("joints", &Model::joints, "The joints (copies).")
      .def_property_readonly("frames", &Model::frames, "The frames (copies), indexed by frame id.")
      .def("frame_id", &Model::frame_id, py::arg("name"), "Frame index by name; ConfigError when unknown.")
      .def("has_frame", &Model::has_frame, py::arg("name"), "Whether the model has a frame of that name.")
      .def("joint_id", &Model::joint_id, py::arg("name"), "Joint index by name; ConfigError when unknown.")
      .def("body_inertia", &Model::body_inertia, py::arg("body"), "Body i's inertia in its frame (a copy).")
      .def_property_readonly("base_link", &Model::base_link)
      .def_property_readonly("tip_link", &Model::tip_link)
      .def_property_readonly("gravity", &Model::gravity)
      .def_property_readonly("base_placement", &Model::base_placement)
      .def_property_readonly("lower_limits", &Model::lower_limits, "[rad or m]; -inf when unbounded.")
      .def_property_readonly("upper_limits", &Model::upper_limits)
      .def_property_readonly("velocity_limits", &Model::velocity_limits)
      .def_property_readonly("effort_limits", &Model::effort_limits)
      .def("total_mass", &Model::total_mass, "Mass of the moving bodies [kg].")
      .def("__repr__", [](const Model& model) {
        return "<phri.Model '" + model.name() + "' " + std::to_string(model.nq()) + " joints, " + model.base_link() +
               " -> " + model.tip_link() + ">";
      });
}

// Data's buffers as read-only views (owner: the Data object).
template <class Member>
void data_view(py::class_<Data>& c, const char* name, Member member, const char* doc) {
  c.def_property_readonly(
      name, [member](py::object self) { return matrix_view(self.cast<const Data&>().*member, self); }, doc);
}

void bind_data(py::module_& m) {
  py::class_<Data> c(m, "Data", "Every buffer the algorithms write, sized once from a Model. Its arrays are views.");
  c.def(py::init<const Model&>(), py::arg("model"));
  data_view(c, "mass_matrix", &Data::mass_matrix, "M(q), after crba or compute_all_terms (n x n view).");
  c.def_property_readonly("tau", [](py::object self) { return vector_view(self.cast<const Data&>().tau, self); },
                          "rnea's output (view).");
  c.def_property_readonly("nonlinear_effects",
                          [](py::object self) { return vector_view(self.cast<const Data&>().nonlinear_effects, self); },
                          "h(q, qd) = C qd + g (view).");
  c.def_property_readonly("gravity_torque",
                          [](py::object self) { return vector_view(self.cast<const Data&>().gravity_torque, self); },
                          "g(q) (view).");
  c.def_property_readonly("coriolis_transpose_qd",
                          [](py::object self) { return vector_view(self.cast<const Data&>().coriolis_transpose_qd, self); },
                          "C(q, qd)^T qd (view).");
  c.def("body_placement", [](py::object self, int i) {
        const Data& d = self.cast<const Data&>();
        check_index("Data.body_placement", i, static_cast<long>(d.body_placements.size()));
        return isometry_view(d.body_placements[static_cast<std::size_t>(i)], self);
      }, py::arg("body"), "Body i in the world, a 4 x 4 view (after forward_kinematics).");
  c.def("frame_placement", [](py::object self, int i) {
        const Data& d = self.cast<const Data&>();
        check_index("Data.frame_placement", i, static_cast<long>(d.frame_placements.size()));
        return isometry_view(d.frame_placements[static_cast<std::size_t>(i)], self);
      }, py::arg("frame"), "Frame i in the world, a 4 x 4 view (after update_frame_placements or compute_all_terms).");
}

// frame_jacobian into `out` (checked: the C++ function writes through an Eigen map of its memory) or a new array.
py::array_t<double> jacobian_into(const Model& model, const Data& data, int frame_id, ReferenceFrame rf, std::optional<py::array> out) {
  check_index("frame_jacobian", frame_id, model.num_frames());
  const auto size = static_cast<py::ssize_t>(sizeof(double));
  py::array target = out ? *out : py::array(py::dtype::of<double>(), {6, model.nv()}, {size, 6 * size});
  const bool usable = target.dtype().is(py::dtype::of<double>()) && target.ndim() == 2 && target.shape(0) == 6 &&
                      target.shape(1) == model.nv() && target.strides(0) == size && target.strides(1) == 6 * size &&
                      target.writeable();
  if (!usable) {
    throw ArgumentError("frame_jacobian: out must be a writeable float64 array of shape (6, " + std::to_string(model.nv()) +
                        ") in Fortran order, e.g. numpy.zeros((6, " + std::to_string(model.nv()) + "), order='F')");
  }
  Eigen::Map<Eigen::MatrixXd> jacobian(static_cast<double*>(target.mutable_data()), 6, model.nv());
  frame_jacobian(model, data, frame_id, rf, jacobian);
  return py::reinterpret_borrow<py::array_t<double>>(target);
}

// A joint vector as the function it enters names it: its size (the library's check_size wording,
// naming this function, not the one it calls first) and finite entries (NaN in, NaN out would be
// silent).
const Vector& joint_vector(const char* function, const char* name, const Vector& v, long expected) {
  check_size(function, name, v.size(), expected);
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throw ArgumentError(std::string(function) + ": " + name + "[" + std::to_string(i) + "] is not finite");
    }
  }
  return v;
}

void bind_kinematics(py::module_& m) {
  m.def("forward_kinematics", py::overload_cast<const Model&, Data&, const Vector&>(&forward_kinematics),
        py::arg("model"), py::arg("data"), py::arg("q"), "Body placements and joint motion subspaces.");
  m.def("forward_kinematics", py::overload_cast<const Model&, Data&, const Vector&, const Vector&>(&forward_kinematics),
        py::arg("model"), py::arg("data"), py::arg("q"), py::arg("qd"), "... and body velocities.");
  m.def("forward_kinematics",
        py::overload_cast<const Model&, Data&, const Vector&, const Vector&, const Vector&>(&forward_kinematics),
        py::arg("model"), py::arg("data"), py::arg("q"), py::arg("qd"), py::arg("qdd"),
        "... and body accelerations (gravity not included).");
  m.def("update_frame_placements", &update_frame_placements, py::arg("model"), py::arg("data"),
        "Frame placements from the body placements (after forward_kinematics).");
  // The frame functions index Data's placements: a bad id is an ArgumentError here, not a stray read.
  using FrameFunction = Vector6d (*)(const Model&, const Data&, int, ReferenceFrame);
  auto checked = [](const char* name, FrameFunction f) {
    return [name, f](const Model& model, const Data& data, int frame_id, ReferenceFrame rf) {
      check_index(name, frame_id, model.num_frames());
      return f(model, data, frame_id, rf);
    };
  };
  m.def("frame_velocity", checked("frame_velocity", &frame_velocity), py::arg("model"), py::arg("data"),
        py::arg("frame_id"), py::arg("rf"), "Frame twist (linear; angular) in convention rf, after forward_kinematics with qd.");
  m.def("frame_acceleration", checked("frame_acceleration", &frame_acceleration), py::arg("model"), py::arg("data"),
        py::arg("frame_id"), py::arg("rf"), "Classical frame acceleration, after forward_kinematics with qd and qdd.");
  m.def("frame_jdot_qdot", checked("frame_jdot_qdot", &frame_jdot_qdot), py::arg("model"), py::arg("data"),
        py::arg("frame_id"), py::arg("rf"), "J̇ q̇ of the frame (after compute_all_terms).");
  m.def("frame_jacobian", &jacobian_into, py::arg("model"), py::arg("data"), py::arg("frame_id"), py::arg("rf"),
        py::arg("out") = py::none(),
        "6 x nv frame Jacobian (after forward_kinematics). `out`: a writeable float64 Fortran-order (6, nv) array, "
        "filled in place (no copy, no allocation); otherwise a new array is returned.");
  m.def("body_point_linear_jacobian",
        [](const Model& model, const Data& data, int body, const Eigen::Vector3d& point) {
          Eigen::MatrixXd j(3, model.nv());
          body_point_linear_jacobian(model, data, body, point, j);
          return j;
        },
        py::arg("model"), py::arg("data"), py::arg("body"), py::arg("point"),
        "3 x nv linear Jacobian of the point of `body` now at world position `point`.");
  m.def("body_point_velocity", &body_point_velocity, py::arg("model"), py::arg("data"), py::arg("body"), py::arg("point"),
        "World velocity of the point of `body` now at `point` (after forward_kinematics with qd).");
  m.def("body_point_jdot_qdot", &body_point_jdot_qdot, py::arg("model"), py::arg("data"), py::arg("body"), py::arg("point"),
        "That point's classical acceleration; with qdd = 0 (after compute_all_terms) its J̇ q̇.");
}

void bind_dynamics(py::module_& m) {
  m.def("crba", [](const Model& model, Data& data, const Vector& q) {
        return matrix_view(crba(model, data, joint_vector("crba", "q", q, model.nq())), owner_of(data));
      }, py::arg("model"), py::arg("data"), py::arg("q"), "M(q) (composite rigid-body algorithm): a view of data.mass_matrix.");
  m.def("compute_mass_matrix_cholesky", &compute_mass_matrix_cholesky, py::arg("data"),
        "Cholesky factor of data.mass_matrix; False if M is not positive definite.");
  m.def("mass_matrix_solve_in_place", &mass_matrix_solve_in_place, py::arg("data"), py::arg("x"),
        "x <- M^-1 x in place: x must be a writeable contiguous float64 vector (after compute_mass_matrix_cholesky).");
  m.def("rnea", [](const Model& model, Data& data, const Vector& q, const Vector& qd, const Vector& qdd) {
        return data_vector(data, rnea(model, data, joint_vector("rnea", "q", q, model.nq()),
                                      joint_vector("rnea", "qd", qd, model.nv()), joint_vector("rnea", "qdd", qdd, model.nv())));
      }, py::arg("model"), py::arg("data"), py::arg("q"), py::arg("qd"), py::arg("qdd"),
      "tau = M(q) qdd + h(q, qd) (recursive Newton-Euler): a view of data.tau.");
  m.def("nonlinear_effects", [](const Model& model, Data& data, const Vector& q, const Vector& qd) {
        return data_vector(data, nonlinear_effects(model, data, joint_vector("nonlinear_effects", "q", q, model.nq()),
                                                   joint_vector("nonlinear_effects", "qd", qd, model.nv())));
      }, py::arg("model"), py::arg("data"), py::arg("q"), py::arg("qd"), "h(q, qd) = C qd + g: a view of data.nonlinear_effects.");
  m.def("compute_gravity", [](const Model& model, Data& data, const Vector& q) {
        return data_vector(data, compute_gravity(model, data, joint_vector("compute_gravity", "q", q, model.nq())));
      }, py::arg("model"), py::arg("data"), py::arg("q"), "g(q): a view of data.gravity_torque.");
  m.def("coriolis_transpose_times_velocity", [](const Model& model, Data& data) {
        return data_vector(data, coriolis_transpose_times_velocity(model, data));
      }, py::arg("model"), py::arg("data"), "C(q, qd)^T qd (after compute_all_terms): a view of data.coriolis_transpose_qd.");
  m.def("compute_all_terms", [](const Model& model, Data& data, const Vector& q, const Vector& qd) {
        return compute_all_terms(model, data, joint_vector("compute_all_terms", "q", q, model.nq()),
                                 joint_vector("compute_all_terms", "qd", qd, model.nv()));
      }, py::arg("model"), py::arg("data"), py::arg("q"), py::arg("qd"),
        "FK, velocities, drift accelerations, M and its Cholesky factor, h, g: the controller's one pass.");
}

}  // namespace

void bind_model(py::module_& m) {
  bind_model_types(m);
  bind_model_options(m);
  bind_model_class(m);
  bind_data(m);
  bind_kinematics(m);
  bind_dynamics(m);
}

}  // namespace phri::python
