#include <phri/sim/mujoco_handles.hpp>

#include <mujoco/mujoco.h>

namespace phri {

void MjModelDeleter::operator()(mjModel_* model) const noexcept { mj_deleteModel(model); }

void MjDataDeleter::operator()(mjData_* data) const noexcept { mj_deleteData(data); }

}  // namespace phri
