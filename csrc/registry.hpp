// One registry per extensible concept on the C++ side (laws, robust terms, criteria, paths): each
// component registers itself by its Python twin's name at load time, from the file that defines
// it, so nothing else names it. Names are resolved once, when a run is built, never in the loop.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>

namespace nnrobust {

// The factories of the components derived from `Base`, each built from `Args...`.
template <class Base, class... Args>
struct Registry {
  // a function (the shipped components') or a closure over a law compiled apart (bindings.cpp)
  using Factory = std::function<std::unique_ptr<Base>(Args...)>;

  static bool add(const std::string &name, Factory factory) {
    table()[name] = factory;
    return true;
  }
  // nullptr when nothing is registered under `name`
  static Factory find(const std::string &name) {
    const auto it = table().find(name);
    return it == table().end() ? nullptr : it->second;
  }

 private:
  static std::map<std::string, Factory> &table() {
    static std::map<std::string, Factory> factories;
    return factories;
  }
};

}  // namespace nnrobust
