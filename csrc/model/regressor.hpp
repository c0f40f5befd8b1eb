// Pinocchio's joint torque regressor Y(q, q', q''), with Y phi = M(q) q'' + N(q, q') for the bodies'
// inertial parameters phi (ten per body, pinocchio.Inertia.toDynamicParameters' order): the twin
// of nnrobust/model/regressor.py's torque_regressor, shared by Slotine-Li's law
// (csrc/controllers/laws/slotine_li.cpp) and identification's batched rows (bindings.cpp).
#pragma once

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "../types.hpp"

namespace nnrobust {

// Into Y (nv x 10 (njoints - 1), sized by the caller: no allocation): body i's regressor
// bodyRegressor(v_i, a_i + g_i) (local frame, a_i with the base's -g), moved to the world frame,
// gives joint j's row block J_j^T oMi* Y_i for every joint j on the path from i to the base.
// Built from calls the pin wheel's library instantiates (instantiating
// computeJointTorqueRegressor itself took a unit's compiler to 2.2 GB).
void joint_torque_regressor(const pinocchio::Model &model, pinocchio::Data &data, const Vector &q, const Vector &v,
                            const Vector &a, Matrix &Y);

}  // namespace nnrobust
