#include "criterion.hpp"

#include <stdexcept>

#include "../model/nominal.hpp"

namespace nnrobust {

void DetAtQ::need() {
  if (done) return;
  det = det_small(ts.J * ts.J.transpose());
  gradient = model.det_gradient(q, ts);
  done = true;
}

void DetAtQ::chain(Matrix &points, std::vector<Matrix> &jacobians) { model.chain(q, points, jacobians); }

Criteria::Criteria(const LoopSpec &spec) : weights(spec.criterion_weights), JJt_(Matrix::Zero(spec.m, spec.m)) {
  if (spec.criterion_params.size() != spec.criteria.size())
    throw std::invalid_argument("LoopSpec.criterion_params: one table of fields per criterion");
  for (size_t i = 0; i < spec.criteria.size(); ++i) {
    const auto factory = CriterionRegistry::find(spec.criteria[i]);
    if (!factory) throw std::invalid_argument("LoopSpec.criteria: unknown criterion " + spec.criteria[i]);
    terms.push_back(factory(Fields{"LoopSpec.criterion_params: the criterion " + spec.criteria[i],
                                         spec.criterion_params[i]}));
  }
  if (weights.size() != static_cast<long>(terms.size()))
    throw std::invalid_argument("LoopSpec.criterion_weights: one weight per criterion");
}

Vector Criteria::gradient(Nominal &model, const Vector &q, const TaskState &ts) const {
  DetAtQ det{model, q, ts};
  Vector grad = Vector::Zero(q.size());
  for (size_t c = 0; c < terms.size(); ++c) grad += weights[c] * terms[c]->gradient(q, det);
  return grad;
}

double Criteria::value(const Vector &q, const Matrix &J, const Matrix &points) const {
  JJt_.noalias() = J * J.transpose();
  const double det = det_small(JJt_);
  double h = 0.0;
  for (size_t c = 0; c < terms.size(); ++c) h += weights[c] * terms[c]->value(q, det, points);
  return h;
}

}  // namespace nnrobust
