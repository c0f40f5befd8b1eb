// A component's numbers as its Python twin declares them (twin_fields): 2-D arrays by name (a
// number is 1 x 1, a vector k x 1). There are no defaults on this side: a missing field is an
// error that names the component and the field.
#pragma once

#include <map>
#include <string>

#include "types.hpp"

namespace nnrobust {

// A component's fields by name, as LoopSpec carries them.
using Params = std::map<std::string, Matrix>;

struct NNROBUST_API Fields {
  std::string owner;  // what the fields are of, for errors: "the law slotine-li", "the criterion obstacles"
  const Params &values;

  const Matrix &matrix(const std::string &name) const;
  Vector vector(const std::string &name) const;  // a k x 1 field
  Vector vector(const std::string &name, Eigen::Index size) const;  // a size x 1 field
  double scalar(const std::string &name) const;  // a 1 x 1 field
};

}  // namespace nnrobust
