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

// The workspaces of christoffel_regressor, sized by their owner (a call allocates none).
struct ChristoffelWork {
  Vector velocity, acceleration;
  Matrix body;  // 6 x 10 (njoints - 1): each body's regressor, the two passes' difference
  ChristoffelWork() = default;
  ChristoffelWork(int nv, int columns) : velocity(Vector::Zero(nv)), acceleration(Vector::Zero(nv)), body(Matrix::Zero(6, columns)) {}
};

// Into Y: Y phi = M(q) a + C(q, v) w + G(q), C the Christoffel Coriolis matrix (M' - 2C skew).
// N(q, v) - G(q) = C(q, v) v is quadratic in v and C(q, v) w its symmetric bilinear form, so by
// polarisation 4 Y = Y(q, v + w, 2a; 2g) - Y(q, v - w, -2a; -2g) (g: gravity, scaled in the
// base's acceleration). The two passes share the placements and the Jacobians, and the
// difference of their body regressors is moved to the world and projected once: about 1.3 calls
// of joint_torque_regressor where Y(q, 0, a) + (Y(q, v + w, 0) - Y(q, v - w, 0)) / 4 takes three
// (SlotineLi.regressor, the same form).
void christoffel_regressor(const pinocchio::Model &model, pinocchio::Data &data, const Vector &q, const Vector &v,
                           const Vector &w, const Vector &a, Matrix &Y, ChristoffelWork &work);

}  // namespace nnrobust
