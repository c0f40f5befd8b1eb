// Work buffers kept per size: an Eigen resize reallocates, so code whose sizes change from one
// call to the next (the joints at rest, the free joints) keeps one set of buffers per size.
#pragma once

#include <memory>
#include <vector>

namespace nnrobust {

// One `Work` per size 1..n, each made (as Work(size)) the first time that size is asked for and
// kept: after the first time, asking for a size allocates nothing.
template <class Work>
class PerSize {
 public:
  Work &at(int n, int size) {
    if (works_.empty()) works_.resize(n);
    std::unique_ptr<Work> &work = works_[size - 1];
    if (!work) work = std::make_unique<Work>(size);
    return *work;
  }

 private:
  std::vector<std::unique_ptr<Work>> works_;
};

}  // namespace nnrobust
