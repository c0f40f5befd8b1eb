// The Eigen types every part of csrc/ speaks (without Pinocchio's headers, for the small parts).
#pragma once

#include <Eigen/Dense>

namespace nnrobust {
using Vector = Eigen::VectorXd;
using Matrix = Eigen::MatrixXd;

inline double sign(double x) { return (x > 0) - (x < 0); }  // numpy.sign
}  // namespace nnrobust
