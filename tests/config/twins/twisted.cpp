// The twin of test_kinds.py's Twisted criterion, compiled apart (nnrobust/twin.hpp):
// h = -0.5 (c^T q)^2 with c = (twist, -1, 1, -1, ...).
#include "nnrobust/twin.hpp"

namespace {

struct Twisted : nnrobust::Criterion {
  double twist;
  explicit Twisted(const nnrobust::Fields &f) : twist(f.scalar("twist")) {}

  nnrobust::Vector coefficients(Eigen::Index n) const {
    nnrobust::Vector c(n);
    for (Eigen::Index i = 0; i < n; ++i) c[i] = i == 0 ? twist : (i % 2 == 1 ? -1.0 : 1.0);
    return c;
  }
  double value(const nnrobust::Vector &q, double, const nnrobust::Matrix &) const override {
    const double cq = coefficients(q.size()).dot(q);
    return -0.5 * cq * cq;
  }
  nnrobust::Vector gradient(const nnrobust::Vector &q, nnrobust::DetAtQ &) const override {
    const nnrobust::Vector c = coefficients(q.size());
    return -c.dot(q) * c;
  }
};

NNROBUST_CRITERION("twisted", Twisted);

}  // namespace
