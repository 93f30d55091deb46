// Forward kinematics, frame placements, frame velocities and accelerations, frame Jacobians.
// Everything is computed in the world frame (see spatial.hpp), so a chain needs no per-joint
// change of coordinates: joint i's motion subspace S_i is expressed once, in world axes.
#include <phri/model/algorithms.hpp>

#include <phri/core/error.hpp>
#include <phri/core/batch_math.hpp>

#include <algorithm>

namespace phri {
namespace {

// Placement of body i in the world and its motion subspace, for the joint position qi whose cosine
// and sine are cos_qi and sin_qi.
void place_body(const Model& model, Data& data, int i, double qi, double cos_qi, double sin_qi) {
  const Joint& joint = model.joint(i);
  const Eigen::Isometry3d& parent = i == 0 ? model.base_placement() : data.body_placements[static_cast<std::size_t>(i - 1)];
  Eigen::Isometry3d& body = data.body_placements[static_cast<std::size_t>(i)];
  body = parent * joint.placement;  // the joint frame at q = 0
  const Eigen::Vector3d axis_world = body.linear() * joint.axis;
  if (joint.type == JointType::kPrismatic) {
    body.translation() += axis_world * qi;
    data.motion_subspace.col(i) << axis_world, Eigen::Vector3d::Zero();
  } else {
    if (joint.axis == Eigen::Vector3d::UnitZ()) {
      // R Rz(q): only the first two columns turn (most arms' URDFs put every joint on z).
      const double c = cos_qi, s = sin_qi;
      auto r = body.linear();
      const Eigen::Vector3d x = r.col(0), y = r.col(1);
      r.col(0) = c * x + s * y;
      r.col(1) = c * y - s * x;
    } else {
      // Rodrigues: Rot(a, q) = c Id + s [a]x + (1 - c) a a^T.
      const Eigen::Vector3d& a = joint.axis;
      const double c = cos_qi, s = sin_qi;
      Eigen::Matrix3d turn = (1.0 - c) * a * a.transpose();
      turn.diagonal().array() += c;
      turn(0, 1) -= s * a.z();
      turn(1, 0) += s * a.z();
      turn(0, 2) += s * a.y();
      turn(2, 0) -= s * a.y();
      turn(1, 2) -= s * a.x();
      turn(2, 1) += s * a.x();
      body.linear() = body.linear() * turn;
    }
    // A rotation about the axis through the body origin p moves the world-origin point at p x a.
    data.motion_subspace.col(i) << body.translation().cross(axis_world), axis_world;
  }
}

const Eigen::Isometry3d& frame_parent_placement(const Model& model, const Data& data, int body) {
  return body < 0 ? model.base_placement() : data.body_placements[static_cast<std::size_t>(body)];
}

// Every body placed from the base out, the joints' sines and cosines taken batch_math::kWidth at a
// time; each(i) runs right after body i is placed.
template <class Each>
void place_bodies(const Model& model, Data& data, const Eigen::VectorXd& q, const Each& each) {
  constexpr int kWidth = batch_math::kWidth;
  double sin_q[kWidth], cos_q[kWidth];
  for (int start = 0; start < model.nq(); start += kWidth) {
    const int count = std::min(kWidth, model.nq() - start);
    batch_math::sincos(q.data() + start, count, sin_q, cos_q);
    for (int k = 0; k < count; ++k) {
      place_body(model, data, start + k, q[start + k], cos_q[k], sin_q[k]);
      each(start + k);
    }
  }
}

}  // namespace

void forward_kinematics(const Model& model, Data& data, const Eigen::VectorXd& q) {
  check_size("forward_kinematics", "q", q.size(), model.nq());
  place_bodies(model, data, q, [](int) {});
}

void forward_kinematics(const Model& model, Data& data, const Eigen::VectorXd& q,
                        const Eigen::VectorXd& qd) {
  check_size("forward_kinematics", "q", q.size(), model.nq());
  check_size("forward_kinematics", "qd", qd.size(), model.nv());
  place_bodies(model, data, q, [&](int i) {
    auto v = data.body_velocities.col(i);
    v = data.motion_subspace.col(i) * qd[i];
    if (i > 0) v += data.body_velocities.col(i - 1);
  });
}

void forward_kinematics(const Model& model, Data& data, const Eigen::VectorXd& q,
                        const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  check_size("forward_kinematics", "qdd", qdd.size(), model.nv());
  forward_kinematics(model, data, q, qd);
  for (int i = 0; i < model.nq(); ++i) {
    const Vector6d s = data.motion_subspace.col(i);
    // d/dt (S_i qd_i) = S_i qdd_i + (v_i x S_i) qd_i: the axis moves with the parent body.
    Vector6d a = s * qdd[i] + motion_cross(data.body_velocities.col(i), s) * qd[i];
    if (i > 0) a += data.body_accelerations.col(i - 1);
    data.body_accelerations.col(i) = a;
  }
}

void update_frame_placements(const Model& model, Data& data) {
  for (int f = 0; f < model.num_frames(); ++f) {
    const Frame& frame = model.frame(f);
    data.frame_placements[static_cast<std::size_t>(f)] =
        frame_parent_placement(model, data, frame.body) * frame.placement;
  }
}

Vector6d frame_velocity(const Model& model, const Data& data, int frame_id, ReferenceFrame rf) {
  const Frame& frame = model.frame(frame_id);
  if (frame.body < 0) return Vector6d::Zero();
  const Vector6d v = data.body_velocities.col(frame.body);
  if (rf == ReferenceFrame::kWorld) return v;
  const Eigen::Isometry3d& oMf = data.frame_placements[static_cast<std::size_t>(frame_id)];
  Vector6d out;
  out.head<3>() = v.head<3>() + v.tail<3>().cross(oMf.translation());
  out.tail<3>() = v.tail<3>();
  if (rf == ReferenceFrame::kLocal) {
    out.head<3>() = oMf.linear().transpose() * out.head<3>();
    out.tail<3>() = oMf.linear().transpose() * out.tail<3>();
  }
  return out;
}

Vector6d frame_acceleration(const Model& model, const Data& data, int frame_id, ReferenceFrame rf) {
  const Frame& frame = model.frame(frame_id);
  if (frame.body < 0) return Vector6d::Zero();
  const Vector6d a = data.body_accelerations.col(frame.body);
  if (rf == ReferenceFrame::kWorld) return a;  // d/dt(J_world qd) is the spatial acceleration
  const Vector6d v = data.body_velocities.col(frame.body);
  const Eigen::Isometry3d& oMf = data.frame_placements[static_cast<std::size_t>(frame_id)];
  const Eigen::Vector3d& p = oMf.translation();
  const Eigen::Vector3d w = v.tail<3>();
  const Eigen::Vector3d alpha = a.tail<3>();
  // Acceleration of the body point at p, seen from a frame moving with the point's velocity.
  const Eigen::Vector3d a_point = a.head<3>() + alpha.cross(p);
  Vector6d out;
  if (rf == ReferenceFrame::kLocalWorldAligned) {
    // Classical acceleration: add w x (velocity of the point).
    const Eigen::Vector3d v_point = v.head<3>() + w.cross(p);
    out.head<3>() = a_point + w.cross(v_point);
    out.tail<3>() = alpha;
  } else {
    // d/dt(R^T x) = R^T (x' - w x x): the rotating axes remove exactly that term.
    out.head<3>() = oMf.linear().transpose() * a_point;
    out.tail<3>() = oMf.linear().transpose() * alpha;
  }
  return out;
}

void frame_jacobian(const Model& model, const Data& data, int frame_id, ReferenceFrame rf,
                    Eigen::Ref<Eigen::MatrixXd> jacobian) {
  check_size("frame_jacobian", "jacobian rows", jacobian.rows(), 6);
  check_size("frame_jacobian", "jacobian cols", jacobian.cols(), model.nv());
  const Frame& frame = model.frame(frame_id);
  const int columns = frame.body + 1;  // the joints that move the frame; the rest are zero
  jacobian.rightCols(model.nv() - columns).setZero();
  if (rf == ReferenceFrame::kWorld) {
    jacobian.leftCols(columns) = data.motion_subspace.leftCols(columns);
    return;
  }
  const Eigen::Isometry3d& oMf = data.frame_placements[static_cast<std::size_t>(frame_id)];
  const Eigen::Vector3d p = oMf.translation();
  for (int j = 0; j < columns; ++j) {
    const auto s = data.motion_subspace.col(j);
    Eigen::Vector3d lin = s.head<3>() + s.tail<3>().cross(p);
    Eigen::Vector3d ang = s.tail<3>();
    if (rf == ReferenceFrame::kLocal) {
      lin = oMf.linear().transpose() * lin;
      ang = oMf.linear().transpose() * ang;
    }
    jacobian.col(j) << lin, ang;
  }
}

void body_point_linear_jacobian(const Model& model, const Data& data, int body, const Eigen::Vector3d& point,
                                Eigen::Ref<Eigen::MatrixXd> jacobian) {
  check_size("body_point_linear_jacobian", "jacobian rows", jacobian.rows(), 3);
  check_size("body_point_linear_jacobian", "jacobian cols", jacobian.cols(), model.nv());
  jacobian.setZero();
  for (int j = 0; j <= body; ++j) {
    const auto s = data.motion_subspace.col(j);
    jacobian.col(j) = s.head<3>() + s.tail<3>().cross(point);
  }
}

Eigen::Vector3d body_point_velocity(const Model&, const Data& data, int body, const Eigen::Vector3d& point) {
  if (body < 0) return Eigen::Vector3d::Zero();
  const auto v = data.body_velocities.col(body);
  return v.head<3>() + v.tail<3>().cross(point);
}

Eigen::Vector3d body_point_jdot_qdot(const Model&, const Data& data, int body, const Eigen::Vector3d& point) {
  if (body < 0) return Eigen::Vector3d::Zero();
  const auto v = data.body_velocities.col(body);
  const auto a = data.body_accelerations.col(body);
  const Eigen::Vector3d w = v.tail<3>();
  const Eigen::Vector3d v_point = v.head<3>() + w.cross(point);
  return a.head<3>() + a.tail<3>().cross(point) + w.cross(v_point);
}

}  // namespace phri
