#include "regressor.hpp"

#include <pinocchio/algorithm/regressor.hpp>

#include "../pin_calls.hpp"

namespace nnrobust {

void joint_torque_regressor(const pinocchio::Model &model, pinocchio::Data &data, const Vector &q, const Vector &v,
                            const Vector &a, Matrix &Y) {
  pin::forwardKinematics(model, data, q, v, a);
  const pin::Matrix6x &J = pin::computeJointJacobians(model, data);
  const pinocchio::Motion base(-model.gravity.linear(), Eigen::Vector3d::Zero());  // a_gf[0] = -g
  Y.setZero();
  for (int i = 1; i < model.njoints; ++i) {
    const pinocchio::Motion a_gf = data.a[i] + data.oMi[i].actInv(base);
    const Eigen::Matrix<double, 6, 10> world =
        data.oMi[i].toDualActionMatrix() * pinocchio::bodyRegressor(data.v[i], a_gf);
    for (int j = i; j > 0; j = static_cast<int>(model.parents[j]))
      Y.block(model.idx_vs[j], 10 * (i - 1), model.nvs[j], 10).noalias() =
          J.middleCols(model.idx_vs[j], model.nvs[j]).transpose() * world;
  }
}

}  // namespace nnrobust
