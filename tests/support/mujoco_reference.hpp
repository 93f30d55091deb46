#pragma once
// MuJoCo 2.2.2 as an independent dynamics reference for tests: loads an MJCF (file or string),
// sets (q, qd, qdd) in phri's joint order (matched by joint name) and returns MuJoCo's M, bias
// forces, inverse dynamics, body/site poses and point Jacobians.
#include <phri/model/model.hpp>

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace phri::test {

class MujocoReference {
public:
  static MujocoReference from_file(const std::string& path) {
    char error[1024] = "";
    mjModel* m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
    if (m == nullptr) throw std::runtime_error("MuJoCo could not load " + path + ": " + error);
    return MujocoReference(m);
  }
  static MujocoReference from_string(const std::string& xml) {
    auto vfs = std::make_unique<mjVFS>();
    mj_defaultVFS(vfs.get());
    if (mj_makeEmptyFileVFS(vfs.get(), "model.xml", static_cast<int>(xml.size())) != 0) {
      throw std::runtime_error("MuJoCo VFS full");
    }
    const int index = mj_findFileVFS(vfs.get(), "model.xml");
    std::memcpy(vfs->filedata[index], xml.data(), xml.size());
    char error[1024] = "";
    mjModel* m = mj_loadXML("model.xml", vfs.get(), error, sizeof(error));
    mj_deleteVFS(vfs.get());
    if (m == nullptr) throw std::runtime_error(std::string("MuJoCo could not load the MJCF: ") + error);
    return MujocoReference(m);
  }

  MujocoReference(MujocoReference&& o) noexcept : m_(o.m_), d_(o.d_), qpos_(std::move(o.qpos_)), dof_(std::move(o.dof_)) {
    o.m_ = nullptr;
    o.d_ = nullptr;
  }
  ~MujocoReference() {
    if (d_) mj_deleteData(d_);
    if (m_) mj_deleteModel(m_);
  }

  /// Map phri's joints to MuJoCo's qpos/dof addresses by name.
  void bind(const phri::Model& model) {
    qpos_.clear();
    dof_.clear();
    for (const auto& joint : model.joints()) {
      const int id = mj_name2id(m_, mjOBJ_JOINT, joint.name.c_str());
      if (id < 0) throw std::runtime_error("MuJoCo model has no joint " + joint.name);
      qpos_.push_back(m_->jnt_qposadr[id]);
      dof_.push_back(m_->jnt_dofadr[id]);
    }
  }
  int nv() const { return m_->nv; }

  void set_state(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
    mj_resetData(m_, d_);
    for (std::size_t i = 0; i < qpos_.size(); ++i) {
      d_->qpos[qpos_[i]] = q[static_cast<Eigen::Index>(i)];
      d_->qvel[dof_[i]] = qd[static_cast<Eigen::Index>(i)];
      d_->qacc[dof_[i]] = qdd[static_cast<Eigen::Index>(i)];
    }
    mj_forward(m_, d_);  // positions, velocities, M (qM) and bias forces; qacc is overwritten
    for (std::size_t i = 0; i < qpos_.size(); ++i) d_->qacc[dof_[i]] = qdd[static_cast<Eigen::Index>(i)];
  }

  Eigen::MatrixXd mass_matrix() const {
    std::vector<mjtNum> full(static_cast<std::size_t>(m_->nv * m_->nv));
    mj_fullM(m_, full.data(), d_->qM);
    Eigen::MatrixXd out(qpos_.size(), qpos_.size());
    for (std::size_t i = 0; i < dof_.size(); ++i) {
      for (std::size_t j = 0; j < dof_.size(); ++j) {
        out(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = full[static_cast<std::size_t>(dof_[i] * m_->nv + dof_[j])];
      }
    }
    return out;
  }
  Eigen::VectorXd bias() const { return gather(d_->qfrc_bias); }
  /// mj_rne with the accelerations of set_state (flg_acc = 1): M qdd + bias, armature excluded.
  Eigen::VectorXd rne_with_acceleration() {
    std::vector<mjtNum> out(static_cast<std::size_t>(m_->nv));
    mj_rne(m_, d_, 1, out.data());
    return gather(out.data());
  }
  /// mj_inverse: M qdd + bias with armature included (no passive or constraint forces here).
  Eigen::VectorXd inverse() {
    mj_inverse(m_, d_);
    return gather(d_->qfrc_inverse);
  }

  bool has_body(const std::string& name) const { return mj_name2id(m_, mjOBJ_BODY, name.c_str()) >= 0; }
  bool has_site(const std::string& name) const { return mj_name2id(m_, mjOBJ_SITE, name.c_str()) >= 0; }
  Eigen::Isometry3d body_pose(const std::string& name) const {
    const int id = mj_name2id(m_, mjOBJ_BODY, name.c_str());
    return pose(d_->xpos + 3 * id, d_->xmat + 9 * id);
  }
  Eigen::Isometry3d site_pose(const std::string& name) const {
    const int id = mj_name2id(m_, mjOBJ_SITE, name.c_str());
    return pose(d_->site_xpos + 3 * id, d_->site_xmat + 9 * id);
  }
  int body_of_site(const std::string& name) const {
    return m_->site_bodyid[mj_name2id(m_, mjOBJ_SITE, name.c_str())];
  }
  int body_id(const std::string& name) const { return mj_name2id(m_, mjOBJ_BODY, name.c_str()); }
  /// 6 x n Jacobian of the body point at world position `point`: (translational; rotational).
  Eigen::MatrixXd point_jacobian(int body, const Eigen::Vector3d& point) const {
    std::vector<mjtNum> jacp(static_cast<std::size_t>(3 * m_->nv)), jacr(static_cast<std::size_t>(3 * m_->nv));
    const mjtNum p[3] = {point.x(), point.y(), point.z()};
    mj_jac(m_, d_, jacp.data(), jacr.data(), p, body);
    Eigen::MatrixXd out(6, static_cast<Eigen::Index>(dof_.size()));
    for (std::size_t j = 0; j < dof_.size(); ++j) {
      for (int r = 0; r < 3; ++r) {
        out(r, static_cast<Eigen::Index>(j)) = jacp[static_cast<std::size_t>(r * m_->nv + dof_[j])];
        out(3 + r, static_cast<Eigen::Index>(j)) = jacr[static_cast<std::size_t>(r * m_->nv + dof_[j])];
      }
    }
    return out;
  }
  const mjModel* model() const { return m_; }
  mjModel* model_mutable() { return m_; }
  mjData* data() { return d_; }

private:
  explicit MujocoReference(mjModel* m) : m_(m), d_(mj_makeData(m)) {}
  static Eigen::Isometry3d pose(const mjtNum* pos, const mjtNum* mat) {
    Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
    out.translation() << pos[0], pos[1], pos[2];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) out.linear()(r, c) = mat[3 * r + c];
    }
    return out;
  }
  Eigen::VectorXd gather(const mjtNum* v) const {
    Eigen::VectorXd out(static_cast<Eigen::Index>(dof_.size()));
    for (std::size_t i = 0; i < dof_.size(); ++i) out[static_cast<Eigen::Index>(i)] = v[dof_[i]];
    return out;
  }

  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  std::vector<int> qpos_;
  std::vector<int> dof_;
};

}  // namespace phri::test
