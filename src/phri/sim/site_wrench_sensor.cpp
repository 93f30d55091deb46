#include <phri/sim/site_wrench_sensor.hpp>

#include <mujoco/mujoco.h>

#include <cstddef>

namespace phri {
namespace {

// MuJoCo's own spatial products (engine_util_spatial.c), which its API does not export, written as
// MuJoCo writes them. MuJoCo (Debian's build) multiplies and adds separately; our code is built
// with FMA (-march=x86-64-v3), and a fused multiply-add rounds once where MuJoCo rounds twice:
// contraction off, so that the results are MuJoCo's to the bit.
#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")

// res = cinert * v (MuJoCo's mju_mulInertVec).
void mul_inert_vec(mjtNum res[6], const mjtNum i[10], const mjtNum v[6]) {
  res[0] = i[0] * v[0] + i[3] * v[1] + i[4] * v[2] - i[8] * v[4] + i[7] * v[5];
  res[1] = i[3] * v[0] + i[1] * v[1] + i[5] * v[2] + i[8] * v[3] - i[6] * v[5];
  res[2] = i[4] * v[0] + i[5] * v[1] + i[2] * v[2] - i[7] * v[3] + i[6] * v[4];
  res[3] = i[8] * v[1] - i[7] * v[2] + i[9] * v[3];
  res[4] = i[6] * v[2] - i[8] * v[0] + i[9] * v[4];
  res[5] = i[7] * v[0] - i[6] * v[1] + i[9] * v[5];
}

// res = vel x* f, the spatial cross product for forces (MuJoCo's mju_crossForce).
void cross_force(mjtNum res[6], const mjtNum vel[6], const mjtNum f[6]) {
  res[0] = -vel[2] * f[1] + vel[1] * f[2];
  res[1] = vel[2] * f[0] - vel[0] * f[2];
  res[2] = -vel[1] * f[0] + vel[0] * f[1];
  res[3] = -vel[2] * f[4] + vel[1] * f[5];
  res[4] = vel[2] * f[3] - vel[0] * f[5];
  res[5] = -vel[1] * f[3] + vel[0] * f[4];

  res[0] += -vel[5] * f[4] + vel[4] * f[5];
  res[1] += vel[5] * f[3] - vel[3] * f[5];
  res[2] += -vel[4] * f[3] + vel[3] * f[4];
}

// cacc = (parent + axis_dot v) + axis a for a body of at most one dof (no axes: none), rounded as
// MuJoCo's mju_mulDofVec (mju_scl, or zeros), mju_add and mju_addTo round it, without their calls.
void one_dof_acceleration(mjtNum cacc[6], const mjtNum parent[6], const mjtNum* axis_dot, const mjtNum* axis,
                          mjtNum v, mjtNum a) {
  for (int k = 0; k < 6; ++k) {
    const mjtNum velocity_term = axis_dot ? axis_dot[k] * v : 0.0;
    const mjtNum acceleration_term = axis ? axis[k] * a : 0.0;
    cacc[k] = parent[k] + velocity_term;
    cacc[k] += acceleration_term;
  }
}

#pragma GCC pop_options

}  // namespace

bool SiteWrenchSensor::reproduces(const mjModel* m, int force_sensor, int torque_sensor) {
  for (int s : {force_sensor, torque_sensor}) {
    if (s < 0 || s >= m->nsensor || m->sensor_cutoff[s] != 0.0) return false;
    if (m->sensor_noise[s] != 0.0 && (m->opt.enableflags & mjENBL_SENSORNOISE)) return false;
  }
  return m->sensor_type[force_sensor] == mjSENS_FORCE && m->sensor_type[torque_sensor] == mjSENS_TORQUE &&
         m->sensor_objid[force_sensor] == m->sensor_objid[torque_sensor] && m->neq == 0;
}

SiteWrenchSensor::SiteWrenchSensor(const mjModel* m, int force_sensor, int /*torque_sensor*/)
    : site_(m->sensor_objid[force_sensor]), body_(m->site_bodyid[site_]) {
  const auto nbody = static_cast<std::size_t>(m->nbody);
  in_subtree_.assign(nbody, 0);
  in_subtree_[static_cast<std::size_t>(body_)] = 1;
  for (int b = body_ + 1; b < m->nbody; ++b) {  // a parent's id is below its children's
    in_subtree_[static_cast<std::size_t>(b)] = in_subtree_[static_cast<std::size_t>(m->body_parentid[b])];
  }
  std::vector<int> ancestors;
  for (int b = m->body_parentid[body_]; b > 0; b = m->body_parentid[b]) ancestors.insert(ancestors.begin(), b);
  for (int b = body_; b < m->nbody; ++b) {
    if (in_subtree_[static_cast<std::size_t>(b)]) subtree_.push_back(b);
  }
  accelerated_ = ancestors;
  accelerated_.insert(accelerated_.end(), subtree_.begin(), subtree_.end());
  for (auto* v : {&cacc_, &cfrc_ext_, &cfrc_int_}) v->assign(6 * nbody, 0.0);
}

// cacc = cacc_parent + cdof_dot qvel + cdof qacc, as mj_rnePostConstraint's forward pass.
void SiteWrenchSensor::accelerate(const mjModel* m, const mjData* d, const double* qvel, int body) {
  const int dofs = m->body_dofnum[body];
  const int adr = m->body_dofadr[body];
  mjtNum* cacc = cacc_.data() + 6 * body;
  const mjtNum* parent = cacc_.data() + 6 * m->body_parentid[body];
  if (dofs == 1) {
    one_dof_acceleration(cacc, parent, d->cdof_dot + 6 * adr, d->cdof + 6 * adr, qvel[adr], d->qacc[adr]);
  } else if (dofs == 0) {
    one_dof_acceleration(cacc, parent, nullptr, nullptr, 0.0, 0.0);
  } else {  // a ball or free joint on the way: MuJoCo's mju_mulDofVec is then a matrix product
    mjtNum tmp[6];
    mju_mulMatTVec(tmp, d->cdof_dot + 6 * adr, qvel + adr, dofs, 6);
    mju_add(cacc, parent, tmp, 6);
    mju_mulMatTVec(tmp, d->cdof + 6 * adr, d->qacc + adr, dofs, 6);
    mju_addTo(cacc, tmp, 6);
  }
}

// The subtree's share of mj_rnePostConstraint's cfrc_ext: the applied forces (xfrc_applied).
void SiteWrenchSensor::add_external_forces(const mjModel* m, const mjData* d) {
  for (int b : subtree_) {
    mjtNum* ext = cfrc_ext_.data() + 6 * b;
    mju_zero(ext, 6);
    mjtNum* applied = d->xfrc_applied + 6 * b;  // mju_isZero takes a non-const pointer; it only reads
    if (mju_isZero(applied, 6)) continue;
    mjtNum torque_force[6], at_com[6];
    mju_copy3(torque_force, applied + 3);
    mju_copy3(torque_force + 3, applied);
    mju_transformSpatial(at_com, torque_force, 1, d->subtree_com + 3 * m->body_rootid[b], d->xipos + 3 * b, nullptr);
    mju_addTo(ext, at_com, 6);
  }
}

// The contacts' share of cfrc_ext, for the contacts that touch the subtree, in MuJoCo's order.
void SiteWrenchSensor::add_contact_forces(const mjModel* m, const mjData* d) {
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& con = d->contact[i];
    if (con.efc_address < 0) continue;
    const int body1 = m->geom_bodyid[con.geom1];
    const int body2 = m->geom_bodyid[con.geom2];
    const bool on1 = body1 > 0 && in_subtree_[static_cast<std::size_t>(body1)];
    const bool on2 = body2 > 0 && in_subtree_[static_cast<std::size_t>(body2)];
    if (!on1 && !on2) continue;
    mjtNum local[6], world[6], at_com[6];
    mj_contactForce(m, d, i, local);
    mju_rotVecMatT(world, local + 3, con.frame);  // torque : force, world axes
    mju_rotVecMatT(world + 3, local, con.frame);
    if (on1) {
      mju_transformSpatial(at_com, world, 1, d->subtree_com + 3 * m->body_rootid[body1], con.pos, nullptr);
      mju_subFrom(cfrc_ext_.data() + 6 * body1, at_com, 6);
    }
    if (on2) {
      mju_transformSpatial(at_com, world, 1, d->subtree_com + 3 * m->body_rootid[body2], con.pos, nullptr);
      mju_addTo(cfrc_ext_.data() + 6 * body2, at_com, 6);
    }
  }
}

// cfrc_int = cinert cacc + cvel x* (cinert cvel) - cfrc_ext, then the children's added to their parents.
void SiteWrenchSensor::internal_forces(const mjModel* m, const mjData* d) {
  for (int b : subtree_) {
    mjtNum body_force[6], inertia_velocity[6], coriolis[6];
    mul_inert_vec(body_force, d->cinert + 10 * b, cacc_.data() + 6 * b);
    mul_inert_vec(inertia_velocity, d->cinert + 10 * b, d->cvel + 6 * b);
    cross_force(coriolis, d->cvel + 6 * b, inertia_velocity);
    mju_addTo(body_force, coriolis, 6);
    mju_sub(cfrc_int_.data() + 6 * b, body_force, cfrc_ext_.data() + 6 * b, 6);
  }
  for (auto it = subtree_.rbegin(); it != subtree_.rend(); ++it) {
    if (*it != body_) mju_addTo(cfrc_int_.data() + 6 * m->body_parentid[*it], cfrc_int_.data() + 6 * *it, 6);
  }
}

void SiteWrenchSensor::evaluate(const mjModel* m, const mjData* d, const double* qvel, double force[3], double torque[3]) {
  mju_zero(cacc_.data(), 6);  // the world's: -gravity
  if (!(m->opt.disableflags & mjDSBL_GRAVITY)) mju_scl3(cacc_.data() + 3, m->opt.gravity, -1);
  for (int b : accelerated_) accelerate(m, d, qvel, b);
  add_external_forces(m, d);
  add_contact_forces(m, d);
  internal_forces(m, d);
  // mj_sensorAcc: the body's interaction force moved to the site, in its frame (torque : force).
  mjtNum at_site[6];
  mju_transformSpatial(at_site, cfrc_int_.data() + 6 * body_, 1, d->site_xpos + 3 * site_,
                       d->subtree_com + 3 * m->body_rootid[body_], d->site_xmat + 9 * site_);
  mju_copy3(force, at_site + 3);
  mju_copy3(torque, at_site);
}

}  // namespace phri
