#include "law.hpp"

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

}  // namespace nnrobust
