#include "fields.hpp"

#include <stdexcept>
#include <string>

namespace nnrobust {

const Matrix &Fields::matrix(const std::string &name) const {
  const auto it = values.find(name);
  if (it == values.end())
    throw std::invalid_argument(owner + " needs the field " + name +
                                " (a law in C++: give controller.params." + name +
                                "; a shipped component: declare it in its Python twin's twin_fields)");
  return it->second;
}

Vector Fields::vector(const std::string &name) const {
  const Matrix &x = matrix(name);
  if (x.cols() != 1) throw std::invalid_argument(owner + ": the field " + name + " is not a vector");
  return x.col(0);
}

Vector Fields::vector(const std::string &name, Eigen::Index size) const {
  Vector x = vector(name);
  if (x.size() != size)
    throw std::invalid_argument(owner + ": the field " + name + " has " + std::to_string(x.size()) + " entries, not " +
                                std::to_string(size));
  return x;
}

double Fields::scalar(const std::string &name) const {
  const Matrix &x = matrix(name);
  if (x.size() != 1) throw std::invalid_argument(owner + ": the field " + name + " is not a number");
  return x(0, 0);
}

}  // namespace nnrobust
