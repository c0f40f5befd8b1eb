// One registry per extensible concept on the C++ side (laws, robust terms, criteria, paths,
// disturbances): each component registers itself by its Python twin's name at load time, from the
// file that defines it, so nothing else names it. Names are resolved once, when a run is built,
// never in the loop. A twin compiled apart (nnrobust/twin.hpp) registers into its own library's
// tables, which the compiled loop copies into its own when it loads the library.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>

#include "types.hpp"

namespace nnrobust {

// The factories of the components derived from `Base`, each built from `Args...`.
template <class Base, class... Args>
struct Registry {
  // a function (the shipped components') or a closure over a law compiled apart (bindings.cpp)
  using Factory = std::function<std::unique_ptr<Base>(Args...)>;
  using Table = std::map<std::string, Factory>;

  static bool add(const std::string &name, Factory factory) {
    table()[name] = factory;
    return true;
  }
  // nullptr when nothing is registered under `name`
  static Factory find(const std::string &name) {
    const auto it = table().find(name);
    return it == table().end() ? nullptr : it->second;
  }
  // every registered name with its factory
  static Table &table() {
    static Table factories;
    return factories;
  }
};

// The names a registry holds, comma-separated; with `into` (the compiled loop's table of the same
// registry), its entries are copied there too. A twin library's hand-over (NNROBUST_SHARE_REGISTRY).
template <class R>
const char *share_registry(void *into) {
  static std::string names;
  names.clear();
  for (const auto &[name, factory] : R::table()) {
    names += (names.empty() ? "" : ",") + name;
    if (into != nullptr) (*static_cast<typename R::Table *>(into))[name] = factory;
  }
  return names.c_str();
}

}  // namespace nnrobust

// In a twin compiled apart (compiled with NNROBUST_TWIN_LIBRARY, nnrobust/native_law.py), each
// registry its file includes is handed over by one exported function, `symbol`; the compiled loop
// looks the five up when it loads the library (bindings.cpp, load_twin_library). Elsewhere, nothing.
#ifdef NNROBUST_TWIN_LIBRARY
#define NNROBUST_SHARE_REGISTRY(R, symbol) \
  extern "C" NNROBUST_API const char *symbol(void *into) { return ::nnrobust::share_registry<R>(into); }
#else
#define NNROBUST_SHARE_REGISTRY(R, symbol)
#endif
