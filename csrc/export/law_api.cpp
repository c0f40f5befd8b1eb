// The C API of an exported law (nnrobust_law.h; docs/export.md): the compiled loop's controller
// (its nominal model, path, criteria and law, csrc/controllers.hpp) built from a description that
// nnrobust/export.py writes from the same LoopSpec and ModelSpec the compiled loop is given, and
// stepped from outside. No Python and no URDF parser: the nominal model arrives as numbers.
//
// The description is text, one entry per line, every number in C's hexadecimal float notation
// (exact; "inf" and "nan" as strtod reads them), strings percent-encoded:
//   nnrobust-law 1                     the format and its version (the first line)
//   # ...                              a comment
//   num KEY x | int KEY i | str KEY =s
//   vec KEY k x1..xk | ints KEY k i1..ik | strs KEY k s1..sk
//   mat KEY r c x11 x12 .. xrc         (row by row)
// KEY names a LoopSpec field (law, m, period, ...), a field of one of its parameter maps
// (law_params/K_D, criterion_params/0/weights) or of the nominal ModelSpec (model/axes); `n` is
// the number of joints.
#include "nnrobust_law.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "../controllers.hpp"
#include "../controllers/laws/law.hpp"
#include "../model/nominal.hpp"
#include "arena.hpp"

namespace {

using nnrobust::Matrix;
using nnrobust::Params;
using nnrobust::Vector;

// Why the last create or step of this thread failed: a fixed buffer, so that reporting an error
// inside a step allocates nothing.
thread_local char last_error[1024] = "";

void set_error(const char *message) {
  std::strncpy(last_error, message, sizeof(last_error) - 1);
  last_error[sizeof(last_error) - 1] = '\0';
}

// The bytes each law reserves for its step's temporaries (the largest step measured, Slotine-Li on
// the Panda, takes a few kB; benchmarks/export_step.py prints the high-water mark).
constexpr std::size_t arena_bytes = std::size_t{1} << 20;

// The law registry is a plain map: adding a user's law (nnrobust_law_add_native) and building a
// controller (which looks its law up) take this lock, so laws may be created on several threads.
std::mutex registry_lock;

// A string as export.py writes it: '=' then its percent-encoding (urllib.parse.quote)
std::string decoded(const std::string &s) {
  if (s.empty() || s[0] != '=') throw std::invalid_argument("a string entry must start with '=': " + s);
  std::string out;
  for (size_t i = 1; i < s.size(); ++i) {
    if (s[i] == '%') {
      const std::string hex = s.substr(i + 1, 2);
      char *end = nullptr;
      const long byte = std::strtol(hex.c_str(), &end, 16);
      if (hex.size() != 2 || end != hex.c_str() + 2) throw std::invalid_argument("a bad %-escape in the string " + s);
      out += static_cast<char>(byte);
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

struct Line {
  std::istringstream in;
  std::string key;
  long number;  // of the line, for errors

  std::string word() {
    std::string w;
    if (!(in >> w)) throw std::invalid_argument("line " + std::to_string(number) + " (" + key + ") ends too soon");
    return w;
  }
  double real() {
    const std::string w = word();
    char *end = nullptr;
    const double x = std::strtod(w.c_str(), &end);
    if (end != w.c_str() + w.size())
      throw std::invalid_argument("line " + std::to_string(number) + " (" + key + "): " + w + " is not a number");
    return x;
  }
  long integer() {
    const std::string w = word();
    char *end = nullptr;
    const long x = std::strtol(w.c_str(), &end, 10);
    if (w.empty() || end != w.c_str() + w.size())
      throw std::invalid_argument("line " + std::to_string(number) + " (" + key + "): " + w + " is not an integer");
    return x;
  }
  Matrix matrix(long rows, long cols) {
    if (rows < 0 || cols < 0 || rows * cols > 100000000)
      throw std::invalid_argument("line " + std::to_string(number) + " (" + key + "): bad shape");
    Matrix x(rows, cols);
    for (long i = 0; i < rows; ++i)
      for (long j = 0; j < cols; ++j) x(i, j) = real();
    return x;
  }
};

std::vector<std::string> split(const std::string &key) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(key);
  while (std::getline(in, part, '/')) parts.push_back(part);
  return parts;
}

}  // namespace

struct nnrobust_law {
  nnrobust::Arena arena{arena_bytes};  // first: destroyed last
  nnrobust::LoopSpec spec;
  nnrobust::ModelSpec model_spec;
  bool has_model = false;
  int n = 0;
  std::unique_ptr<nnrobust::LoadedModel> model;
  std::unique_ptr<nnrobust::Nominal> nominal;
  std::unique_ptr<nnrobust::Controller> controller;  // holds references to spec and nominal
  Vector q, v, z;
  // what a step refuses as absurd (status 2; export.py's absurd_bounds): |tau_i| > command_bound_i,
  // or |q_i - measured_mid_i| > measured_half_i; infinite (nothing refused) when the description
  // gives none (an export written before them)
  Vector command_bound, measured_lower, measured_upper, measured_mid, measured_half;

  explicit nnrobust_law(const char *description) {
    read(description);
    if (n <= 0) throw std::invalid_argument("the description gives no number of joints (int n)");
    if (has_model) model = std::make_unique<nnrobust::LoadedModel>(model_spec);
    if (spec.law.rfind("cpp:", 0) == 0 && !nnrobust::LawRegistry::find(spec.law))
      throw std::invalid_argument("the law " + spec.law +
                                  " is a user's law in C++: create it with nnrobust_law_create of its export's "
                                  "libnnrobust_law (which registers it), or register it with "
                                  "nnrobust_law_add_native first");
    nominal = nnrobust::make_nominal(spec, model.get());
    controller = std::make_unique<nnrobust::Controller>(spec, *nominal);
    q.resize(n);
    v.resize(n);
    z = spec.z0;
    const double inf = std::numeric_limits<double>::infinity();
    for (Vector *bound : {&command_bound, &measured_lower, &measured_upper}) {
      if (bound->size() == 0) *bound = Vector::Constant(n, bound == &measured_lower ? -inf : inf);
      if (bound->size() != n) throw std::invalid_argument("the description's absurd-value bounds need n entries each");
    }
    measured_mid = 0.5 * (measured_lower + measured_upper);
    measured_half = 0.5 * (measured_upper - measured_lower);
    for (int i = 0; i < n; ++i)
      if (!std::isfinite(measured_mid[i])) measured_mid[i] = 0.0, measured_half[i] = inf;
  }

  // Whether the measurement or the command is absurd: one comparison per joint each.
  bool absurd(const Vector &tau) const {
    for (int i = 0; i < n; ++i)
      if (std::abs(q[i] - measured_mid[i]) > measured_half[i] || std::abs(tau[i]) > command_bound[i]) return true;
    return false;
  }

  Params &params(const std::string &name, const std::vector<std::string> &key, long number) {
    if (name == "plant_params") return spec.plant_params;
    if (name == "nominal_params") return spec.nominal_params;
    if (name == "nominal_friction") return spec.nominal_friction;
    if (name == "path_params") return spec.path_params;
    if (name == "pose_params") return spec.pose_params;
    if (name == "law_params") return spec.law_params;
    if (name == "robust_params") return spec.robust_params;
    if (name == "criterion_params" && key.size() == 3) {
      char *end = nullptr;
      const unsigned long i = std::strtoul(key[1].c_str(), &end, 10);
      if (key[1].empty() || end != key[1].c_str() + key[1].size() || i >= 1000)
        throw std::invalid_argument("line " + std::to_string(number) + ": bad criterion index " + key[1]);
      if (spec.criterion_params.size() <= i) spec.criterion_params.resize(i + 1);
      return spec.criterion_params[i];
    }
    throw std::invalid_argument("line " + std::to_string(number) + ": unknown parameter map " + name);
  }

  void set(const std::string &type, Line &line) {
    const std::vector<std::string> key = split(line.key);
    const std::string &k = line.key;
    const auto unknown = [&]() {
      return std::invalid_argument("line " + std::to_string(line.number) + ": unknown " + type + " entry " + k);
    };
    if (key.size() >= 2 && key[0] == "model") {  // the nominal ModelSpec
      has_model = true;
      nnrobust::ModelSpec &ms = model_spec;
      const std::string &f = key[1];
      if (type == "strs") {
        std::vector<std::string> values(static_cast<size_t>(line.integer()));
        for (auto &s : values) s = decoded(line.word());
        if (f == "joint_types") ms.joint_types = values;
        else if (f == "joint_names") ms.joint_names = values;
        else throw unknown();
      } else if (type == "ints" && f == "parents") {
        ms.parents.resize(static_cast<size_t>(line.integer()));
        for (auto &p : ms.parents) p = static_cast<int>(line.integer());
      } else if (type == "mat") {
        const long r = line.integer(), c = line.integer();
        const Matrix x = line.matrix(r, c);
        if (f == "axes") ms.axes = x;
        else if (f == "rotations") ms.rotations = x;
        else if (f == "translations") ms.translations = x;
        else if (f == "inertias") ms.inertias = x;
        else if (f == "frame_rotation" && r == 3 && c == 3) ms.frame_rotation = x;
        else throw unknown();
      } else if (type == "vec") {
        const Vector x = line.matrix(line.integer(), 1);
        if (f == "armature") ms.armature = x;
        else if (f == "gravity" && x.size() == 3) ms.gravity = x;
        else if (f == "frame_translation" && x.size() == 3) ms.frame_translation = x;
        else throw unknown();
      } else if (type == "str" && f == "frame_name") {
        ms.frame_name = decoded(line.word());
      } else if (type == "int" && f == "frame_joint") {
        ms.frame_joint = static_cast<int>(line.integer());
      } else {
        throw unknown();
      }
      return;
    }
    if (key.size() >= 2) {  // a field of a parameter map
      if (type != "mat") throw unknown();
      const long r = line.integer(), c = line.integer();
      params(key[0], key, line.number)[key.back()] = line.matrix(r, c);
      return;
    }
    nnrobust::LoopSpec &s = spec;
    if (type == "num") {
      const double x = line.real();
      if (k == "period") s.period = x;
      else if (k == "pinv_threshold") s.pinv_threshold = x;
      else if (k == "pinv_max_damping") s.pinv_max_damping = x;
      else throw unknown();
    } else if (type == "int") {
      const long x = line.integer();
      if (k == "n") n = static_cast<int>(x);
      else if (k == "m") s.m = static_cast<int>(x);
      else if (k == "law_signals") s.law_signals = static_cast<int>(x);
      else if (k == "pose") s.pose = x != 0;
      else throw unknown();
    } else if (type == "str") {
      const std::string x = decoded(line.word());
      if (k == "nominal") s.nominal = x;
      else if (k == "path") s.path = x;
      else if (k == "law") s.law = x;
      else if (k == "robust") s.robust = x;
      else throw unknown();
    } else if (type == "strs" && k == "criteria") {
      s.criteria.resize(static_cast<size_t>(line.integer()));
      for (auto &c : s.criteria) c = decoded(line.word());
    } else if (type == "vec") {
      const Vector x = line.matrix(line.integer(), 1);
      if (k == "criterion_weights") s.criterion_weights = x;
      else if (k == "z0") s.z0 = x;
      else if (k == "command_bound") command_bound = x;
      else if (k == "measured_lower") measured_lower = x;
      else if (k == "measured_upper") measured_upper = x;
      else throw unknown();
    } else {
      throw unknown();
    }
  }

  void read(const char *description) {
    if (description == nullptr) throw std::invalid_argument("no description (NULL)");
    std::istringstream in(description);
    std::string text;
    long number = 0;
    while (std::getline(in, text)) {
      ++number;
      if (number == 1) {
        if (text != "nnrobust-law 1")
          throw std::invalid_argument("not a law description of this version (its first line must be 'nnrobust-law 1')");
        continue;
      }
      if (text.empty() || text[0] == '#') continue;
      Line line{std::istringstream(text), "", number};
      const std::string type = line.word();
      line.key = line.word();
      set(type, line);
      std::string rest;
      if (line.in >> rest)
        throw std::invalid_argument("line " + std::to_string(number) + " (" + line.key + "): more values than its shape");
    }
    if (number == 0) throw std::invalid_argument("the description is empty");
    spec.criterion_params.resize(spec.criteria.size());
  }
};

extern "C" {

int nnrobust_law_add_native(const char *name, nnrobust_law_function factory) {
  last_error[0] = '\0';
  if (name == nullptr || factory == nullptr) {
    set_error("nnrobust_law_add_native: a NULL argument");
    return -1;
  }
  // the function NNROBUST_USER_LAW defines (csrc/controllers/laws/law.hpp), by its address
  using Make = nnrobust::Law *(*)(const nnrobust::LawParams &, nnrobust::LawContext &);
  const auto make = reinterpret_cast<Make>(factory);
  try {
    std::lock_guard<std::mutex> lock(registry_lock);
    if (!nnrobust::LawRegistry::find(name))
      nnrobust::LawRegistry::add(name, [make](const nnrobust::LawParams &p, nnrobust::LawContext &c) {
        return std::unique_ptr<nnrobust::Law>(make(p, c));
      });
    return 0;
  } catch (const std::exception &err) {
    set_error(err.what());
  }
  return -1;
}

nnrobust_law *nnrobust_law_create_from(const char *description) {
  last_error[0] = '\0';
  try {
    std::lock_guard<std::mutex> lock(registry_lock);
    return new nnrobust_law(description);
  } catch (const std::exception &err) {
    set_error(err.what());
  } catch (...) {
    set_error("unknown error");
  }
  return nullptr;
}

int nnrobust_law_dof(const nnrobust_law *law) { return law ? law->n : 0; }

double nnrobust_law_period(const nnrobust_law *law) { return law ? law->spec.period : std::nan(""); }

int nnrobust_law_step(nnrobust_law *law, double t, const double *q, const double *v, double *tau_out) {
  if (law == nullptr || q == nullptr || v == nullptr || tau_out == nullptr) {
    set_error("nnrobust_law_step: a NULL argument");
    return -1;
  }
  const int n = law->n;
  law->q = Eigen::Map<const Vector>(q, n);
  law->v = Eigen::Map<const Vector>(v, n);
  nnrobust::ArenaScope scope(law->arena);  // every temporary of this step comes from the arena
  try {
    int status = 0;
    {
      const nnrobust::Output out = law->controller->compute(t, law->q, law->v, law->z);
      if (out.tau.size() != n) throw std::length_error("the law returned a torque of the wrong size");
      Eigen::Map<Vector>(tau_out, n) = out.tau;
      if (!out.tau.allFinite()) {
        status = 1;
      } else if (law->absurd(out.tau)) {  // not to be applied: the state is not advanced either
        status = 2;
      } else {
        if (out.z.size() != law->z.size()) throw std::length_error("the law returned a state of the wrong size");
        law->z = out.z;  // the same size: copied into the law's own storage
      }
    }  // every temporary freed
    if (law->arena.live() != 0) {  // the next step would hand that memory out again
      char message[256];
      std::snprintf(message, sizeof(message),
                    "the step kept %ld block(s) of memory it allocated: a law must allocate what it keeps "
                    "from one step to the next in its constructor",
                    law->arena.live());
      set_error(message);
      return -1;
    }
    return status;
  } catch (const std::exception &err) {
    set_error(err.what());
  } catch (...) {
    set_error("unknown error");
  }
  return -1;
}

void nnrobust_law_reset(nnrobust_law *law) {
  if (law) law->z = law->spec.z0;
}

long nnrobust_law_heap_requests(const nnrobust_law *law) {
  if (law == nullptr) return -1;
  return nnrobust::arena_wrapped() ? law->arena.overflows : -1;
}

void nnrobust_law_destroy(nnrobust_law *law) { delete law; }

const char *nnrobust_law_last_error(void) { return last_error; }

}  // extern "C"
