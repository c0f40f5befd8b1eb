// The Eigen types every part of csrc/ speaks (without Pinocchio's headers, for the small parts).
#pragma once

#include <Eigen/Dense>

// The parts a law compiled apart (a user's .cpp, docs/extending.md) calls in the extension: exported
// from it; everything else stays hidden.
#if defined(__GNUC__)
#define NNROBUST_API __attribute__((visibility("default")))
#else
#define NNROBUST_API
#endif

namespace nnrobust {
using Vector = Eigen::VectorXd;
using Matrix = Eigen::MatrixXd;

inline double sign(double x) { return (x > 0) - (x < 0); }  // numpy.sign
}  // namespace nnrobust
