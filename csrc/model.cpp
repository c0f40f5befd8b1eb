#include "model.hpp"

#include <stdexcept>

#include <pinocchio/serialization/model.hpp>

#include "pin_calls.hpp"

namespace nnrobust {

LoadedModel::LoadedModel(const std::string &serialized, const std::string &frame_name) {
  model.loadFromString(serialized);
  data = pinocchio::Data(model);
  if (!model.existFrame(frame_name)) throw std::invalid_argument("unknown frame " + frame_name);
  frame = model.getFrameId(frame_name);
}

Matrix LoadedModel::mass(const Vector &q) {
  pin::crba(model, data, q);
  data.M.triangularView<Eigen::StrictlyLower>() = data.M.transpose().triangularView<Eigen::StrictlyLower>();
  return data.M;
}

Vector LoadedModel::bias(const Vector &q, const Vector &v) {
  return pin::rnea(model, data, q, v, Vector::Zero(model.nv));
}

Matrix LoadedModel::frame_jacobian(const Vector &q) {
  pin::Matrix6x J = pin::Matrix6x::Zero(6, model.nv);
  pin::computeFrameJacobian(model, data, q, frame, pinocchio::LOCAL_WORLD_ALIGNED, J);
  return J;
}

}  // namespace nnrobust
