#include "regressor.hpp"

#include <pinocchio/algorithm/regressor.hpp>

#include "../pin_calls.hpp"

namespace nnrobust {

namespace {

// joint j's row block J_j^T X_i for every body i and every joint j on the path from i to the base,
// X_i the world-frame regressor of body i (6 x 10 each, side by side in world)
void project_to_joints(const pinocchio::Model &model, const pin::Matrix6x &J, int body, const Eigen::Matrix<double, 6, 10> &world,
                       Matrix &Y) {
  for (int j = body; j > 0; j = static_cast<int>(model.parents[j]))
    Y.block(model.idx_vs[j], 10 * (body - 1), model.nvs[j], 10).noalias() =
        J.middleCols(model.idx_vs[j], model.nvs[j]).transpose() * world;
}

}  // namespace

void joint_torque_regressor(const pinocchio::Model &model, pinocchio::Data &data, const Vector &q, const Vector &v,
                            const Vector &a, Matrix &Y) {
  pin::forwardKinematics(model, data, q, v, a);
  const pin::Matrix6x &J = pin::computeJointJacobians(model, data);
  const pinocchio::Motion base(-model.gravity.linear(), Eigen::Vector3d::Zero());  // a_gf[0] = -g
  Y.setZero();
  for (int i = 1; i < model.njoints; ++i) {
    const pinocchio::Motion a_gf = data.a[i] + data.oMi[i].actInv(base);
    project_to_joints(model, J, i, data.oMi[i].toDualActionMatrix() * pinocchio::bodyRegressor(data.v[i], a_gf), Y);
  }
}

void christoffel_regressor(const pinocchio::Model &model, pinocchio::Data &data, const Vector &q, const Vector &v,
                           const Vector &w, const Vector &a, Matrix &Y, ChristoffelWork &work) {
  const int bodies = model.njoints - 1;
  for (const double sign : {1.0, -1.0}) {  // Y(q, v + w, 2a; 2g), then minus Y(q, v - w, -2a; -2g)
    work.velocity = v + sign * w;
    work.acceleration = 2.0 * sign * a;
    pin::forwardKinematics(model, data, q, work.velocity, work.acceleration);
    const pinocchio::Motion base(-2.0 * sign * model.gravity.linear(), Eigen::Vector3d::Zero());
    for (int i = 1; i <= bodies; ++i) {
      const Eigen::Matrix<double, 6, 10> body =
          pinocchio::bodyRegressor(data.v[i], data.a[i] + data.oMi[i].actInv(base));
      if (sign > 0)
        work.body.middleCols<10>(10 * (i - 1)) = body;
      else
        work.body.middleCols<10>(10 * (i - 1)) -= body;
    }
  }
  const pin::Matrix6x &J = pin::computeJointJacobians(model, data);  // the placements at q, as both passes left them
  Y.setZero();
  for (int i = 1; i <= bodies; ++i)
    project_to_joints(model, J, i, 0.25 * (data.oMi[i].toDualActionMatrix() * work.body.middleCols<10>(10 * (i - 1))), Y);
}

}  // namespace nnrobust
