// The Eigen types every part of csrc/ speaks (without Pinocchio's headers, for the small parts).
#pragma once

#include <Eigen/Dense>

namespace nnrobust {
using Vector = Eigen::VectorXd;
using Matrix = Eigen::MatrixXd;
}  // namespace nnrobust
