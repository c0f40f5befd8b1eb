#include "law.hpp"

#include <stdexcept>

namespace nnrobust {

namespace {
std::map<std::string, LawFactory> &laws() {
  static std::map<std::string, LawFactory> registry;
  return registry;
}
}  // namespace

bool register_law(const char *name, LawFactory factory) {
  laws()[name] = factory;
  return true;
}

LawFactory find_law(const std::string &name) {
  const auto it = laws().find(name);
  return it == laws().end() ? nullptr : it->second;
}

const Matrix &LawParams::matrix(const std::string &name) const {
  const auto it = values.find(name);
  if (it == values.end())
    throw std::invalid_argument("LoopSpec.law_params: the law " + law + " needs the field " + name +
                                " (declare it in its Python twin's twin_fields)");
  return it->second;
}

Vector LawParams::vector(const std::string &name) const {
  const Matrix &x = matrix(name);
  if (x.cols() != 1) throw std::invalid_argument("LoopSpec.law_params: " + law + "." + name + " is not a vector");
  return x.col(0);
}

double LawParams::scalar(const std::string &name) const {
  const Matrix &x = matrix(name);
  if (x.size() != 1) throw std::invalid_argument("LoopSpec.law_params: " + law + "." + name + " is not a number");
  return x(0, 0);
}

}  // namespace nnrobust
