// Small tests on a symmetric matrix's spectrum, cheaper than its eigenvalues.
#pragma once

#include <Eigen/Cholesky>

namespace nnrobust {

// Whether every eigenvalue of the symmetric A is above c: A - c I positive definite, by a Cholesky
// factorisation (a fraction of an eigen-solve's cost; the two can disagree only within rounding
// of c, where a caller that needs the exact answer solves for the eigenvalues).
template <class M>
bool eigenvalues_above(const M &A, double c) {
  using Plain = typename M::PlainObject;
  return Eigen::LLT<Plain>(A - c * Plain::Identity(A.rows(), A.cols())).info() == Eigen::Success;
}

}  // namespace nnrobust
