// The self-motion criteria on the C++ side, the twins of nnrobust/subtasks/: each criterion is a
// class in the file named like its Python module, registered by its configuration name with
// NNROBUST_CRITERION and built from the fields its Python declaration gives (twin_fields). The
// weighted sum of eq. (4) is Criteria (WeightedCriteria); names are resolved once, when it is
// built, never compared in the loop.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "../fields.hpp"
#include "../registry.hpp"

namespace nnrobust {

struct LoopSpec;   // closed_loop.hpp
struct Nominal;    // nominal.hpp: the controller's model
struct TaskState;  // nominal.hpp: its task quantities at q

// det(J J^T) of the nominal model's task Jacobian and its gradient at q, computed once when a
// criterion first asks (manipulability.det_and_gradient)
struct NNROBUST_API DetAtQ {
  Nominal &model;
  const Vector &q;
  const TaskState &ts;
  bool done = false;
  double det = 0.0;
  Vector gradient;
  void need();
  // the nominal model's chain at q: joint origins and task frame (rows), and their Jacobians
  void chain(Matrix &points, std::vector<Matrix> &jacobians);
};

struct Criterion {
  virtual ~Criterion() = default;
  // h(q) on the true robot: det = det(J J^T) of its task Jacobian, points = its chain
  virtual double value(const Vector &q, double det, const Matrix &points) const = 0;
  // dh/dq on the nominal model
  virtual Vector gradient(const Vector &q, DetAtQ &det) const = 0;
};

// The criteria by their configuration name
using CriterionRegistry = Registry<Criterion, const Fields &>;

// WeightedCriteria: sum_i w_i h_i over LoopSpec.criteria with their fields (criterion_params)
struct Criteria {
  std::vector<std::unique_ptr<Criterion>> terms;
  Vector weights;

  explicit Criteria(const LoopSpec &spec);  // an unknown name is refused (std::invalid_argument)
  bool empty() const { return terms.empty(); }
  Vector gradient(Nominal &model, const Vector &q, const TaskState &ts) const;
  double value(const Vector &q, const Matrix &J, const Matrix &points) const;

 private:
  mutable Matrix JJt_;  // value's J J^T, sized m x m here: a recorded step allocates nothing
};

}  // namespace nnrobust

// Registers `Class` (constructed as Class(const Fields &)) under the criterion name `name`.
#define NNROBUST_CRITERION(name, Class)                                                                \
  static const bool nnrobust_registered_##Class = ::nnrobust::CriterionRegistry::add(                      \
      name, [](const ::nnrobust::Fields &f) -> std::unique_ptr<::nnrobust::Criterion> {                  \
        return std::make_unique<Class>(f);                                                             \
      })

// a twin compiled apart hands its criteria over (registry.hpp)
NNROBUST_SHARE_REGISTRY(::nnrobust::CriterionRegistry, nnrobust_twin_criteria)
